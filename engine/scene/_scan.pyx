# cython: language_level=3, boundscheck=False, wraparound=False
"""The parser's one fast path: plain entries read straight from the text, compiled.

:func:`scan_plain` reads ``KEY "string"``, ``KEY number``, ``KEY [numbers or simple
items]``, ``KEY ["strings"]``, ``KEY {`` and ``}`` a character at a time, without tokens, and stops where
the text needs the general grammar (comments, expressions, errors, typographic
quotes), leaving the rest to the token path. It must make exactly what the token
path (the reference) would: the same entries, places, expression texts, token
counts and layout marks, and stop at the same character.

Its character classes come from the lexer's definitions (``engine.scene.lexer``),
read into a table at import. The shapes it follows (a NUMBER, a plain number's
follow set, a vector item ``[+-]a[*/+-]b``) are restated here as loops; the property
test in tests/scene/test_fast_path.py is the proof they agree with the token path.
"""

from bisect import bisect_right

from cpython.ref cimport Py_DECREF, Py_INCREF, PyObject
from cpython.tuple cimport PyTuple_SET_ITEM
from libc.math cimport isfinite, isinf

from engine.scene.db import (
    FLOAT,
    INCLUDE,
    INT,
    STRING,
    STRINGVECTOR,
    STRUCTURE,
    VECTOR,
    Block,
    Entry,
    Value,
)
from engine.scene.diagnostics import Loc
from engine.scene.expr import CONSTANTS, OPERATOR_TEXT, number_text, number_value
from engine.scene.lexer import (
    BRACKETS,
    DIGITS,
    ESCAPE,
    NAME_CHARS,
    NAME_START,
    NEWLINE,
    PLAIN_QUOTE,
    QUOTES,
    SPACE_CHARS,
)

cdef object _number_value = number_value
cdef object _number_text = number_text
cdef dict _CONSTANTS = CONSTANTS
cdef dict _OPERATOR_TEXT = OPERATOR_TEXT
cdef Py_UCS4 _END = 0x110000  # what _at reads past the end of the text
cdef Py_UCS4 _QUOTE = PLAIN_QUOTE
cdef tuple _BLANK_LINE = ("",)  # an entry's comments when a blank line is above it

# -- character classes, from the lexer's definitions --------------------------------
cdef enum:
    C_SPACE = 1
    C_NEWLINE = 2
    C_DIGIT = 4
    C_NAME_START = 8
    C_NAME = 16
    C_QUOTE = 32
    C_BRACKET = 64
    C_ESCAPE = 128
    MAX_WIDE = 16

cdef unsigned char _ascii[128]
cdef Py_UCS4 _wide[MAX_WIDE]  # the few classified characters past ASCII, and theirs
cdef unsigned char _wide_class[MAX_WIDE]
cdef int _n_wide = 0


cdef void _mark(str chars, unsigned char flag) except *:
    global _n_wide
    cdef Py_UCS4 c
    cdef int k
    for c in chars:
        if c < 128:
            _ascii[c] |= flag
            continue
        for k in range(_n_wide):
            if _wide[k] == c:
                _wide_class[k] |= flag
                break
        else:
            if _n_wide == MAX_WIDE:
                raise ValueError("too many non-ASCII characters in the lexer's classes")
            _wide[_n_wide] = c
            _wide_class[_n_wide] = flag
            _n_wide += 1


for _chars, _flag in ((SPACE_CHARS, C_SPACE), (NEWLINE, C_NEWLINE), (DIGITS, C_DIGIT),
                      (NAME_START, C_NAME_START), (NAME_CHARS, C_NAME), (QUOTES, C_QUOTE),
                      (BRACKETS, C_BRACKET), (ESCAPE, C_ESCAPE)):
    _mark(_chars, _flag)


cdef inline unsigned char _cls(Py_UCS4 c):
    cdef int k
    if c < 128:
        return _ascii[c]
    for k in range(_n_wide):
        if _wide[k] == c:
            return _wide_class[k]
    return 0


# Places, values, entries and blocks are made here without the calls their classes'
# __new__/__init__ go through (that costs a file like the benchmark's a fifth of its
# reading time). Each sets every field of its class, as the class would: the tests
# compare every field of what both paths make.
cdef object _object_new = object.__new__
cdef type _Loc = Loc


cdef extern from "Python.h":
    PyObject *PyType_GenericAlloc(type t, Py_ssize_t n) except NULL


cdef inline object _loc(object path, Py_ssize_t line, Py_ssize_t col):
    """``Loc(path, line, col)``, made as ``tuple.__new__(Loc, ...)`` makes it."""
    cdef object loc = <object>PyType_GenericAlloc(_Loc, 3)
    Py_DECREF(loc)  # (the cast took a second reference)
    cdef object item = path
    Py_INCREF(item)  # PyTuple_SET_ITEM steals one
    PyTuple_SET_ITEM(loc, 0, item)
    item = line
    Py_INCREF(item)
    PyTuple_SET_ITEM(loc, 1, item)
    item = col
    Py_INCREF(item)
    PyTuple_SET_ITEM(loc, 2, item)
    return loc


cdef inline object _value(object kind, object data, object loc, object expr=None):
    cdef object v = _object_new(Value)
    v.kind = kind
    v.data = data
    v.loc = loc
    v.expr = expr
    return v


cdef inline object _entry(object key, object value, object loc, bint blank):
    cdef object e = _object_new(Entry)
    e.key = key
    e.value = value
    e.loc = loc
    e.comments = _BLANK_LINE if blank else ()
    e.trailing = ()
    e.included = None
    return e


cdef inline object _block(object loc):
    cdef object b = _object_new(Block)
    b.entries = []
    b.loc = loc
    b.open_comment = ()
    b.tail_comments = ()
    b.inline = False
    return b


cdef inline Py_UCS4 _at(str text, Py_ssize_t i, Py_ssize_t n):
    return text[i] if i < n else _END


cdef inline bint _space(Py_UCS4 c):
    """Whitespace other than newline."""
    return _cls(c) & C_SPACE


cdef inline bint _digit(Py_UCS4 c):
    return _cls(c) & C_DIGIT


cdef inline bint _name_start(Py_UCS4 c):
    return _cls(c) & C_NAME_START


cdef inline bint _name_char(Py_UCS4 c):
    return _cls(c) & C_NAME


cdef Py_ssize_t _name_end(str text, Py_ssize_t i, Py_ssize_t n):
    while _name_char(_at(text, i, n)):
        i += 1
    return i


cdef Py_ssize_t _number_end(str text, Py_ssize_t i, Py_ssize_t n, bint *flt):
    """End of the NUMBER lexeme at ``i`` (``lexer.NUMBER_RE`` restated), or -1; ``flt``:
    not an INT."""
    cdef Py_UCS4 c = _at(text, i, n)
    cdef Py_ssize_t j
    flt[0] = False
    if _digit(c):
        while _digit(_at(text, i, n)):
            i += 1
        if _at(text, i, n) == u'.':
            flt[0] = True
            i += 1
            while _digit(_at(text, i, n)):
                i += 1
    elif c == u'.' and _digit(_at(text, i + 1, n)):
        flt[0] = True
        i += 1
        while _digit(_at(text, i, n)):
            i += 1
    else:
        return -1
    c = _at(text, i, n)
    if c == u'e' or c == u'E':
        j = i + 1
        c = _at(text, j, n)
        if c == u'+' or c == u'-':
            j += 1
        if _digit(_at(text, j, n)):
            while _digit(_at(text, j, n)):
                j += 1
            i = j
            flt[0] = True
    return i


cdef object _number(str text, Py_ssize_t a, Py_ssize_t b, bint flt):
    """``expr.number_value`` of ``text[a:b]`` (None when out of range)."""
    cdef long long v = 0
    cdef Py_ssize_t i
    cdef double x
    if flt:
        x = float(text[a:b])
        return None if isinf(x) else x
    if b - a < 16:
        for i in range(a, b):
            v = v * 10 + (<long long>_at(text, i, b) - 48)
        return v
    return _number_value(text[a:b])


cdef object _find(list scopes, str name):
    """A variable from ``scopes`` (innermost last), else a constant; None if unknown."""
    cdef Py_ssize_t k
    cdef dict scope
    for k in range(len(scopes) - 1, -1, -1):
        scope = scopes[k]
        if name in scope:
            return scope[name]
    return _CONSTANTS.get(name)


cdef object _operand(list scopes, str text, Py_ssize_t a, Py_ssize_t b, bint num, bint flt,
                     list texts):
    """An item's number or variable value (None if unknown); appends its text to ``texts``."""
    if num:
        v = _number(text, a, b, flt)
        if v is not None:
            texts.append(_number_text(v))
        return v
    name = text[a:b]
    texts.append(name)
    return _find(scopes, name)


cdef Py_ssize_t _operand_end(str text, Py_ssize_t i, Py_ssize_t n, bint *num, bint *flt):
    """End of a NUMBER or a name at ``i``, or -1."""
    cdef Py_UCS4 c = _at(text, i, n)
    if _name_start(c):
        num[0] = False
        return _name_end(text, i, n)
    num[0] = True
    return _number_end(text, i, n, flt)


# Long: a vector literal in one C loop, its cursor in C locals as scan_plain's
cdef object _vector(list scopes, str text, Py_ssize_t n, Py_ssize_t pos, object loc,
                    object path, Py_ssize_t line, Py_ssize_t line_start, bint signs,
                    Py_ssize_t *end, Py_ssize_t *used):
    """The VECTOR from ``pos`` (after ``[``), or None if an item is not plain.

    Plain items: signed numbers one space apart (split in one pass), else items
    ``[+-]a`` or ``[+-]a OP b`` written without spaces, where a and b are numbers or
    known names and OP one of ``* / + -``. None also where an item has a sign and
    ``signs`` is false (one more nesting level for the token path, which reports it).
    """
    cdef list items = []
    cdef Py_ssize_t i = pos, a, e, e2, s2 = 0, signs_used = 0
    cdef Py_UCS4 c, sign, op
    cdef bint flt, flt2, num, num2, plain
    cdef double x, y
    cdef list texts
    while _space(_at(text, i, n)):
        i += 1
    if _at(text, i, n) == _QUOTE:
        return _strings(text, n, i, loc, path, line, line_start, end, used)
    i = pos
    # Only numbers, one space apart? Check, then read them.
    plain = _at(text, i, n) == u']'
    while not plain:
        c = _at(text, i, n)
        e = _number_end(text, i + (c == u'+' or c == u'-'), n, &flt)
        if e < 0:
            break
        c = _at(text, e, n)
        i = e + 1
        if c == u']':
            plain = True
        elif c != u' ':
            break
    if plain:
        i = pos
        while _at(text, i, n) != u']':
            a = i
            c = _at(text, i, n)
            sign = c if c == u'+' or c == u'-' else 0
            e = _number_end(text, i + (sign != 0), n, &flt)
            v = _number(text, a + (sign != 0), e, flt)
            if v is None or (sign and not signs):
                return None
            if sign:
                signs_used += 1
                if sign == u'-':
                    v = -v
            items.append(_value(INT if type(v) is int else FLOAT, v,
                               _loc(path, line, a - line_start + 1)))
            i = e + (_at(text, e, n) == u' ')
        end[0] = i + 1
        used[0] = 3 + len(items) + signs_used
        return _value(VECTOR, items, loc)
    # One item at a time.
    i = pos
    used[0] = 3
    while True:
        while _space(_at(text, i, n)):
            i += 1
        c = _at(text, i, n)
        if c == u']':
            i += 1
            break
        a = i
        sign = c if c == u'+' or c == u'-' else 0
        if sign:
            i += 1
        e = _operand_end(text, i, n, &num, &flt)
        if e < 0:
            return None
        op = _at(text, e, n)
        e2 = e
        if op == u'*' or op == u'/' or op == u'+' or op == u'-':
            s2 = e + 1
            e2 = _operand_end(text, s2, n, &num2, &flt2)
            if e2 < 0:
                return None
        else:
            op = 0
        c = _at(text, e2, n)
        if not (_space(c) or c == u']'):
            return None
        if sign and not signs:
            return None
        at = _loc(path, line, a - line_start + 1)
        if num and not op:
            v = _number(text, i, e, flt)
            if v is None:
                return None
            used[0] += 2 if sign else 1
            items.append(_value(INT if type(v) is int else FLOAT,
                               -v if sign == u'-' else v, at))
            i = e2
            continue
        texts = [u'-' if sign == u'-' else u'+'] if sign else []
        v = _operand(scopes, text, i, e, num, flt, texts)
        if v is None:
            return None
        x = -float(v) if sign == u'-' else float(v)
        if not op:
            used[0] += 2 if sign else 1
            items.append(_value(FLOAT, x, at, u''.join(texts)))
            i = e2
            continue
        texts.append(_OPERATOR_TEXT[op])
        v = _operand(scopes, text, s2, e2, num2, flt2, texts)
        if v is None:
            return None
        y = float(v)
        if op == u'*':
            x *= y
        elif op == u'/':
            if y == 0:
                return None
            x /= y
        elif op == u'+':
            x += y
        else:
            x -= y
        if not isfinite(x):
            return None
        used[0] += 4 if sign else 3
        items.append(_value(FLOAT, x, at, u''.join(texts)))
        i = e2
    end[0] = i
    return _value(VECTOR, items, loc)


cdef object _strings(str text, Py_ssize_t n, Py_ssize_t i, object loc, object path,
                     Py_ssize_t line, Py_ssize_t line_start, Py_ssize_t *end,
                     Py_ssize_t *used):
    """The STRINGVECTOR from ``i`` (its first ``"``), or None if an item is not a plain
    string (an escape, another quote, a line break) or something else stands between
    them: ``["Door" "Handle"]``, as scenes name nodes (an imported one, every object)."""
    cdef list items = []
    cdef Py_ssize_t a
    cdef Py_UCS4 c
    while True:
        c = _at(text, i, n)
        if c == u']':
            break
        if c != _QUOTE:
            return None
        a = i
        i += 1
        c = _at(text, i, n)
        while not (_cls(c) & (C_QUOTE | C_ESCAPE | C_NEWLINE) or c == _END):
            i += 1
            c = _at(text, i, n)
        if c != _QUOTE:
            return None
        items.append(_value(STRING, text[a + 1:i], _loc(path, line, a - line_start + 1)))
        i += 1
        c = _at(text, i, n)
        if not (_space(c) or c == u']'):
            return None
        while _space(c):
            i += 1
            c = _at(text, i, n)
    end[0] = i + 1
    used[0] = 3 + len(items)
    return _value(STRINGVECTOR, items, loc)


# Long: the scanner's pass over plain entries: its cursor stays in C locals
def scan_plain(p, cur, Py_ssize_t pos, Py_ssize_t count, list entries, dict scope,
               list stack, Py_ssize_t ended):
    """Plain entries from ``pos`` into ``entries``, until one is not plain.

    ``p`` is the parser and ``cur`` its cursor; ``count`` is the token count so far;
    blocks opened go on ``stack`` (see ``parser.Open``; their scopes on ``p.scopes``)
    and are closed at their ``}``. ``ended`` is the line the block's last entry or comment ended on (0:
    none yet), for blank lines. Returns the position and token count after the last
    entry read, where a ``}`` closing the block being read stands (-1 if reading
    stopped elsewhere), and ``ended`` then.
    """
    lexer = cur.lexer
    cdef str text = cur.text
    path = cur.path
    cdef list scopes = p.scopes
    cdef Py_ssize_t n = len(text), max_tokens = lexer.max_tokens
    cdef int nesting = cur.nesting, max_nesting = cur.max_nesting
    starts = lexer.line_starts
    cdef Py_ssize_t line = bisect_right(starts, pos)
    cdef Py_ssize_t line_start = starts[line - 1]
    cdef Py_ssize_t i, at, key_end, vpos, end, used, k, close = -1
    cdef Py_UCS4 c
    cdef bint flt, number, opened
    while True:
        i = pos
        c = _at(text, i, n)
        while _cls(c) & (C_NEWLINE | C_SPACE):
            if _cls(c) & C_NEWLINE:
                line += 1
                line_start = i + 1
            i += 1
            c = _at(text, i, n)
        if c == u'}':
            if count >= max_tokens:
                break
            if not stack:
                close = i
                break
            pos = i + 1
            count += 1
            entry, entries, scope, block, opened_on = stack.pop()
            if <Py_ssize_t>opened_on == line:
                block.inline = True
            ended = line
            scopes.pop()
            nesting -= 1
            if entry.key == INCLUDE:
                entry.included = p._include(entry.value, cur)
            continue
        if not _name_start(c):
            break
        at = i
        key_end = i = _name_end(text, i, n)
        c = _at(text, i, n)
        while _space(c):
            i += 1
            c = _at(text, i, n)
        vpos = i
        used = 2
        number = opened = False
        if c == _QUOTE:
            end = i + 1
            c = _at(text, end, n)
            while not (_cls(c) & (C_QUOTE | C_ESCAPE | C_NEWLINE) or c == _END):
                end += 1
                c = _at(text, end, n)
            if c != _QUOTE:
                break
            value = _value(STRING, text[vpos + 1:end],
                          _loc(path, line, vpos + 1 - line_start))
            end += 1
        elif _digit(c) or c == u'.':
            end = _number_end(text, i, n, &flt)
            if end < 0:
                break
            k = end
            c = _at(text, k, n)
            while _cls(c) & (C_NEWLINE | C_SPACE):
                k += 1
                c = _at(text, k, n)
            # What may follow a plain number: a lexeme that is not an operator, a
            # comment or a bad character (else it is part of an expression or an error).
            if not (k == n or _cls(c) & (C_NAME | C_BRACKET | C_QUOTE)
                    or (c == u'.' and _digit(_at(text, k + 1, n)))):
                break
            lit = _number(text, vpos, end, flt)
            if lit is None:
                break
            value = _value(INT if type(lit) is int else FLOAT, lit,
                          _loc(path, line, vpos - line_start + 1))
            number = True
        elif c == u'{' or c == u'[':
            if nesting >= max_nesting:
                break  # the token path reports the limit
            vloc = _loc(path, line, vpos - line_start + 1)
            if c == u'[':
                value = _vector(scopes, text, n, vpos + 1, vloc, path, line, line_start,
                                nesting + 2 <= max_nesting, &end, &used)
                if value is None:
                    break
            else:
                value = _value(STRUCTURE, _block(vloc), vloc)
                end = vpos + 1
                opened = True
        else:
            break
        if count + used > max_tokens:
            break
        count += used
        pos = end
        key = text[at:key_end]
        entry = _entry(key, value, _loc(path, line, at - line_start + 1),
                       ended and line > ended + 1)
        entries.append(entry)
        ended = line
        if number:
            scope[key] = lit
        if opened:
            block = value.data
            stack.append((entry, entries, scope, block, line))
            entries = block.entries
            scope = {}
            scopes.append(scope)
            nesting += 1
            ended = 0
        elif key == INCLUDE:
            entry.included = p._include(value, cur)
    cur.nesting = nesting
    return pos, count, close, ended
