"""FLOAT EXPRESSIONS: parse, evaluate and write back arithmetic in scene files.

Grammar (usual precedence, ``^`` binds tightest and is right-associative)::

    expr    := term (('+' | '-') term)*
    term    := unary (('*' | '/') unary)*
    unary   := ('-' | '+') unary | power
    power   := primary ('^' unary)?
    primary := NUMBER | NAME | FUNC '(' expr (',' expr)* ')' | '(' expr ')'

Inside a vector, items are separated by spaces, so ``[1 -2]`` is two items while
``[1 - 2]`` and ``[1-2]`` are one: a sign with a space before it and none after
starts a new item. Names are scalar keys defined earlier (same or enclosing
block) or the constants ``pi`` and ``e``. Random functions draw from the numpy
Generator handed to the parser, so one seed reproduces a scene.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine.scene.diagnostics import Loc, quoted, suggest
from engine.scene.lexer import EOF, IDENT, NUMBER, PUNCT, Lexer, Token

CONSTANTS = {"pi": math.pi, "e": math.e}
MAX_EXPR_DEPTH = 256


class ExprError(Exception):
    """An expression problem at ``loc``; the parser turns it into a diagnostic."""

    def __init__(self, loc: Loc, message: str):
        super().__init__(message)
        self.loc = loc
        self.message = message


def _rand_interval(rng: np.random.Generator, a: float, b: float) -> float:
    return float(rng.uniform(a, b))


def _rand_normal(rng: np.random.Generator, mean: float, sd: float) -> float:
    return float(rng.normal(mean, abs(sd)))


def _rand_int(rng: np.random.Generator, a: float, b: float) -> float:
    lo, hi = math.ceil(min(a, b)), math.floor(max(a, b))
    return float(rng.integers(lo, hi + 1)) if lo <= hi else float(lo)


#: name -> (fewest arguments, most (None: no limit), function, draws from the rng)
FUNCTIONS: dict[str, tuple[int, int | None, Callable[..., float], bool]] = {
    "randInterval": (2, 2, _rand_interval, True),
    "randNormal": (2, 2, _rand_normal, True),
    "randInt": (2, 2, _rand_int, True),
    "sin": (1, 1, math.sin, False),
    "cos": (1, 1, math.cos, False),
    "tan": (1, 1, math.tan, False),
    "asin": (1, 1, math.asin, False),
    "acos": (1, 1, math.acos, False),
    "atan": (1, 1, math.atan, False),
    "atan2": (2, 2, math.atan2, False),
    "sqrt": (1, 1, math.sqrt, False),
    "abs": (1, 1, abs, False),
    "exp": (1, 1, math.exp, False),
    "log": (1, 1, math.log, False),
    "floor": (1, 1, lambda x: float(math.floor(x)), False),
    "ceil": (1, 1, lambda x: float(math.ceil(x)), False),
    "round": (1, 1, lambda x: float(round(x)), False),
    "deg": (1, 1, math.degrees, False),
    "rad": (1, 1, math.radians, False),
    "min": (2, None, min, False),
    "max": (2, None, max, False),
    "clamp": (3, 3, lambda x, lo, hi: min(max(x, lo), hi), False),
}


@dataclass(slots=True)
class Num:
    value: int | float
    depth: int = 1


@dataclass(slots=True)
class Var:
    name: str
    loc: Loc
    depth: int = 1


@dataclass(slots=True)
class Call:
    name: str
    args: list
    loc: Loc
    depth: int = 1


@dataclass(slots=True)
class Unary:
    op: str
    operand: object
    depth: int = 1


@dataclass(slots=True)
class Bin:
    op: str
    left: object
    right: object
    loc: Loc
    depth: int = 1


Node = Num | Var | Call | Unary | Bin


class Cursor:
    """A position in a lexer's tokens, shared by the scene parser and the expression parser.

    Tokens are scanned as the cursor reaches them (:meth:`at`); past EOF it stays on EOF.
    """

    def __init__(self, lexer: Lexer, max_nesting: int):
        self.lexer = lexer
        self.tokens = lexer.tokens
        self.i = 0
        self.path = lexer.path
        self.nesting = 0
        self.max_nesting = max_nesting

    def at(self, i: int) -> Token:
        tokens = self.tokens
        while i >= len(tokens):
            if self.lexer.done:
                return tokens[-1]
            self.lexer.next_token()
        return tokens[i]

    @property
    def tok(self) -> Token:
        return self.at(self.i)

    def peek(self, k: int = 1) -> Token:
        return self.at(self.i + k)

    def advance(self) -> Token:
        t = self.at(self.i)
        if t.kind != EOF:
            self.i += 1
        return t

    def loc(self, t: Token | None = None) -> Loc:
        t = t or self.tok
        return Loc(self.path, t.line, t.col)

    def enter(self, t: Token) -> None:
        """Count one nesting level; refuse past the limit instead of overflowing the stack."""
        self.nesting += 1
        if self.nesting > self.max_nesting:
            raise NestingError(self.loc(t), f"nesting deeper than {self.max_nesting} levels "
                                            "(limit); flatten the file")

    def leave(self) -> None:
        self.nesting -= 1


class NestingError(ExprError):
    """Past the nesting limit: parsing of the whole file stops here."""


def describe(t: Token) -> str:
    if t.kind == EOF:
        return "end of file"
    return f"'{quoted(t.text, 20)}'"


def parse_expression(cur: Cursor, in_vector: bool = False) -> Node:
    node = _term(cur, in_vector)
    while True:
        t = cur.tok
        if t.kind != PUNCT or t.text not in "+-":
            return node
        if in_vector and t.space_before and not cur.peek().space_before:
            return node  # ``[1 -2]``: the sign starts the next item
        cur.advance()
        node = _bin(t.text, node, _term(cur, in_vector), cur.loc(t))


def _bin(op: str, left: Node, right: Node, loc: Loc) -> Bin:
    depth = max(left.depth, right.depth) + 1
    if depth > MAX_EXPR_DEPTH:
        raise NestingError(loc, f"expression deeper than {MAX_EXPR_DEPTH} operations (limit)")
    return Bin(op, left, right, loc, depth)


def _term(cur: Cursor, in_vector: bool) -> Node:
    node = _unary(cur, in_vector)
    while cur.tok.kind == PUNCT and cur.tok.text in "*/":
        t = cur.advance()
        node = _bin(t.text, node, _unary(cur, in_vector), cur.loc(t))
    return node


def _unary(cur: Cursor, in_vector: bool) -> Node:
    t = cur.tok
    if t.kind == PUNCT and t.text in "+-":
        cur.advance()
        cur.enter(t)
        operand = _unary(cur, in_vector)
        cur.leave()
        return Unary(t.text, operand, operand.depth + 1)
    node = _primary(cur, in_vector)
    if cur.tok.kind == PUNCT and cur.tok.text == "^":
        op = cur.advance()
        cur.enter(op)
        node = _bin("^", node, _unary(cur, in_vector), cur.loc(op))
        cur.leave()
    return node


def _primary(cur: Cursor, in_vector: bool) -> Node:
    t = cur.tok
    if t.kind == NUMBER:
        cur.advance()
        return Num(number(cur, t))
    if t.kind == IDENT:
        cur.advance()
        if t.text in FUNCTIONS and cur.tok.kind == PUNCT and cur.tok.text == "(":
            return _call(cur, t)
        return Var(t.text, cur.loc(t))
    if t.kind == PUNCT and t.text == "(":
        cur.advance()
        cur.enter(t)
        node = parse_expression(cur)
        cur.leave()
        _expect(cur, ")", t)
        return node
    raise ExprError(cur.loc(t), f"expected a number, name or '(' but found {describe(t)}")


def _call(cur: Cursor, name: Token) -> Call:
    open_ = cur.advance()
    cur.enter(open_)
    args = [parse_expression(cur)]
    while cur.tok.kind == PUNCT and cur.tok.text == ",":
        cur.advance()
        args.append(parse_expression(cur))
    cur.leave()
    _expect(cur, ")", open_)
    return Call(name.text, args, cur.loc(name), max(a.depth for a in args) + 1)


def _expect(cur: Cursor, text: str, opener: Token) -> None:
    t = cur.tok
    if t.kind == PUNCT and t.text == text:
        cur.advance()
        return
    raise ExprError(cur.loc(t), f"expected '{text}' to close '{opener.text}' from line "
                                f"{opener.line}:{opener.col} but found {describe(t)}")


def number(cur: Cursor, t: Token) -> int | float:
    v = number_value(t.text)
    if v is None:
        if _is_float(t.text):
            raise ExprError(cur.loc(t), f"number {describe(t)} is too large for a FLOAT")
        raise ExprError(cur.loc(t), f"integer {describe(t)} is out of range (max 2^63-1)")
    return v


def number_value(s: str) -> int | float | None:
    """The value of a NUMBER lexeme: INT without '.' or exponent; None when out of range."""
    if len(s) < 16 and s.isdigit():
        return int(s)
    if _is_float(s):
        v = float(s)
        return None if math.isinf(v) else v
    if len(s) > 19 or int(s) >= 2**63:
        return None
    return int(s)


def _is_float(s: str) -> bool:
    return "." in s or "e" in s or "E" in s


def number_text(v: int | float) -> str:
    """A number as :func:`unparse` writes it (floats round-trip exactly)."""
    return str(v) if isinstance(v, int) else repr(v)


def literal(node: Node) -> int | float | None:
    """The value of a plain (optionally signed) number, else None."""
    if isinstance(node, Num):
        return node.value
    if isinstance(node, Unary) and isinstance(node.operand, Num):
        return -node.operand.value if node.op == "-" else node.operand.value
    return None


def evaluate(node: Node, lookup: Callable[[str], float | None],
             names: Callable[[Loc], list[str]], rng: np.random.Generator) -> float:
    """Evaluate ``node``; ``lookup`` resolves variables and ``names`` lists them for a
    "did you mean" at a place (empty where no hint is wanted). Raises ExprError with a
    location."""
    try:
        value = _eval(node, lookup, names, rng)
    except (OverflowError, ZeroDivisionError, ValueError) as exc:
        raise ExprError(_first_loc(node), f"cannot evaluate expression: {_why(exc)}") from None
    if not math.isfinite(value):
        raise ExprError(_first_loc(node), "expression result is not a finite number")
    return value


def _why(exc: Exception) -> str:
    if isinstance(exc, ZeroDivisionError):
        return "division by zero"
    if isinstance(exc, OverflowError):
        return "result too large"
    return f"math domain error ({exc})"


def _first_loc(node: Node) -> Loc:
    if isinstance(node, Var | Call | Bin):
        return node.loc
    if isinstance(node, Unary):
        return _first_loc(node.operand)
    return Loc("", 0, 0)


def _eval(node: Node, lookup, names, rng) -> float:
    if isinstance(node, Num):
        return float(node.value)
    if isinstance(node, Bin):
        a = _eval(node.left, lookup, names, rng)
        b = _eval(node.right, lookup, names, rng)
        op = node.op
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            if b == 0:
                raise ExprError(node.loc, "division by zero")
            return a / b
        if a < 0 and not float(b).is_integer():
            raise ExprError(node.loc, "negative number raised to a fractional power")
        return math.pow(a, b)
    if isinstance(node, Unary):
        v = _eval(node.operand, lookup, names, rng)
        return -v if node.op == "-" else v
    if isinstance(node, Var):
        v = lookup(node.name)
        if v is None:
            v = CONSTANTS.get(node.name)
        if v is None:
            hint = suggest(node.name, [*names(node.loc), *CONSTANTS, *FUNCTIONS])
            if not hint and node.name[:1].isalpha():
                hint = f' (a string needs quotes: "{quoted(node.name)}")'
            raise ExprError(node.loc, f"unknown variable '{quoted(node.name)}'{hint}")
        return float(v)
    assert isinstance(node, Call)
    fewest, most, fn, random = FUNCTIONS[node.name]
    given = len(node.args)
    if given < fewest or (most is not None and given > most):
        takes = (f"at least {fewest} arguments" if most is None else
                 f"{fewest} argument{'s' if fewest != 1 else ''}")
        raise ExprError(node.loc, f"{node.name}() takes {takes}, got {given}")
    args = [_eval(a, lookup, names, rng) for a in node.args]
    return float(fn(rng, *args) if random else fn(*args))


_PREC = {"+": 1, "-": 1, "*": 2, "/": 2, "^": 4}
#: How :func:`unparse` writes each binary operator (spaced when it binds loosest).
OPERATOR_TEXT = {op: f" {op} " if p == 1 else op for op, p in _PREC.items()}


def _prec(node: Node) -> int:
    if isinstance(node, Bin):
        return _PREC[node.op]
    return 3 if isinstance(node, Unary) else 5


def unparse(node: Node) -> str:
    """Canonical text that parses back to the same tree (also inside a vector)."""
    if isinstance(node, Num):
        return number_text(node.value)
    if isinstance(node, Var):
        return node.name
    if isinstance(node, Call):
        return f"{node.name}({', '.join(unparse(a) for a in node.args)})"
    if isinstance(node, Unary):
        inner = unparse(node.operand)
        return node.op + (f"({inner})" if _prec(node.operand) < 3 else inner)
    p = _PREC[node.op]
    left, right = unparse(node.left), unparse(node.right)
    if node.op == "^":
        left_paren, right_paren = _prec(node.left) < 5, _prec(node.right) < 3
    else:
        left_paren, right_paren = _prec(node.left) < p, _prec(node.right) <= p
    if left_paren:
        left = f"({left})"
    if right_paren:
        right = f"({right})"
    return f"{left}{OPERATOR_TEXT[node.op]}{right}"
