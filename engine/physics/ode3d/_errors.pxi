# ODE's error, debug and message handlers, and the guard around the step.
#
# What ODE permits (libode 0.16, see docs/ODE.md): dError and dDebug (a failed argument or
# internal assertion: two bodies of one joint, a bounding box past integer range, a zero
# vector to normalise) call the installed handler and then exit(1) or abort() when it
# returns. The only way out is not to return: the handler longjmps back to the guard the
# binding set before calling into ODE. Nothing C++ unwinds on the way, so whatever ODE was
# doing is left half done (a space left locked, a step's arena in use): the world is
# unusable afterwards and is abandoned, never called again. The engine's checks therefore
# have to keep every such case away from ODE; this is the last line, which turns the
# abort of the whole process into one message and a physics that stops.

cdef extern from *:
    """
    #include <setjmp.h>
    #include <stdarg.h>
    #include <stdio.h>
    #include <string.h>
    #include <ode/ode.h>

    static __thread jmp_buf* colosseum_ode_jump = NULL;
    static __thread int colosseum_ode_code = 0;
    static __thread char colosseum_ode_text[1024];
    static __thread int colosseum_ode_note_count = 0;
    static __thread char colosseum_ode_note[512];

    /* dError and dDebug: remember the message; jump back to the guard when there is
       one. Without one ODE ends the process when this returns: say why first. */
    static void colosseum_ode_fail(int errnum, const char* msg, va_list ap) {
        jmp_buf* to = colosseum_ode_jump;
        vsnprintf(colosseum_ode_text, sizeof colosseum_ode_text, msg, ap);
        colosseum_ode_code = errnum ? errnum : -1;
        if (to != NULL) {
            colosseum_ode_jump = NULL;
            longjmp(*to, 1);
        }
        fprintf(stderr, "colosseum: ODE internal error %d outside the step: %s\\n"
                "colosseum: the engine's checks should have refused what caused it; "
                "ODE now ends the process (please report this)\\n",
                errnum, colosseum_ode_text);
        fflush(stderr);
    }

    /* dMessage: informational (an LCP that did not converge); counted per thread, the
       first one's text kept, and told by the backend after the step. */
    static void colosseum_ode_message(int errnum, const char* msg, va_list ap) {
        (void)errnum;
        if (colosseum_ode_note_count++ == 0)
            vsnprintf(colosseum_ode_note, sizeof colosseum_ode_note, msg, ap);
    }

    static void colosseum_ode_install(void) {
        dSetErrorHandler(colosseum_ode_fail);
        dSetDebugHandler(colosseum_ode_fail);
        dSetMessageHandler(colosseum_ode_message);
    }

    /* Run one step (the binding's collide-and-solve) with the guard set: 0 when done,
       1 when ODE failed inside. */
    typedef int (*colosseum_ode_body)(void*);
    static int colosseum_ode_guarded(colosseum_ode_body body, void* arg, int* result) {
        jmp_buf here;
        colosseum_ode_code = 0;
        if (setjmp(here)) {
            colosseum_ode_jump = NULL;
            return 1;
        }
        colosseum_ode_jump = &here;
        *result = body(arg);
        colosseum_ode_jump = NULL;
        return 0;
    }

    /* Some of ODE's checks print to stdout instead of calling a handler (dCreateConvex:
       "WARNING: Polygon N is not defined counterclockwise", "Plane N does not contain the
       origin"). Around such a call the process's stdout goes to a temporary file, whose
       text is then handed to the engine's logging. */
    #include <unistd.h>
    static FILE* colosseum_stdout_begin(int* saved) {
        FILE* tmp;
        fflush(stdout);
        *saved = -1;
        tmp = tmpfile();
        if (tmp == NULL) return NULL;
        *saved = dup(1);
        if (*saved < 0 || dup2(fileno(tmp), 1) < 0) {
            if (*saved >= 0) close(*saved);
            *saved = -1;
            fclose(tmp);
            return NULL;
        }
        return tmp;
    }
    static int colosseum_stdout_end(FILE* tmp, int saved, char* out, int size) {
        size_t n;
        if (tmp == NULL) return 0;
        fflush(stdout);
        dup2(saved, 1);
        close(saved);
        rewind(tmp);
        n = fread(out, 1, (size_t)(size - 1), tmp);
        out[n] = 0;
        fclose(tmp);
        return (int)n;
    }

    static const char* colosseum_ode_failure(void) { return colosseum_ode_text; }
    static int colosseum_ode_failure_code(void) { return colosseum_ode_code; }
    static int colosseum_ode_take_notes(char* out, int size) {
        int n = colosseum_ode_note_count;
        if (n && size > 0) {
            strncpy(out, colosseum_ode_note, size - 1);
            out[size - 1] = 0;
        }
        colosseum_ode_note_count = 0;
        return n;
    }
    """
    void install_handlers "colosseum_ode_install"() noexcept nogil
    ctypedef int (*guarded_body "colosseum_ode_body")(void*) noexcept nogil
    int guarded "colosseum_ode_guarded"(guarded_body body, void* arg,
                                        int* result) noexcept nogil
    const char* ode_failure "colosseum_ode_failure"() noexcept nogil
    int ode_failure_code "colosseum_ode_failure_code"() noexcept nogil
    int take_notes_c "colosseum_ode_take_notes"(char* out, int size) noexcept nogil
    ctypedef struct CFILE "FILE"
    CFILE* stdout_begin "colosseum_stdout_begin"(int* saved) noexcept nogil
    int stdout_end "colosseum_stdout_end"(CFILE* tmp, int saved, char* out,
                                          int size) noexcept nogil


class OdeFailure(RuntimeError):
    """ODE failed inside a step (an internal or argument assertion); the world it was
    stepping is abandoned. The message is ODE's."""


def take_notes() -> tuple:
    """ODE's informational messages on this thread since the last call: (how many, the
    first one's text)."""
    cdef char text[512]
    cdef int n = take_notes_c(text, sizeof(text))
    return n, ((<char*>text).decode("utf-8", "replace") if n else "")


#: What ODE printed to stdout during the calls made under ``printed_by`` (lines), until
#: :func:`take_printed` takes them.
_printed = []


def take_printed() -> list:
    """The lines ODE printed to stdout since the last call (see ``colosseum_stdout_begin``),
    for the backend to log; the list emptied."""
    lines = list(_printed)
    _printed.clear()
    return lines


cdef void keep_printed(const char* text, int n) noexcept:
    if n > 0:
        _printed.extend(line for line in (<bytes>text[:n]).decode("utf-8", "replace")
                        .splitlines() if line.strip())
