"""The ``sorpia`` command (also ``python -m sorpia``).

Subcommands, one module each: ``fit`` (control mesh whose limit surface
interpolates a mesh file), ``compare`` (the paper's Table 1 and Figure 7 for
one mesh), ``render`` (the paper's Figure 3), ``info`` (mesh statistics, the
paper's Table 2), ``repair`` (a mesh made valid, sorpia.repair) and ``demo``
(all of it on a generated sample mesh);
``parser`` holds their options, ``output`` the files they write besides
meshes, ``progress`` the progress line, ``common`` what they share.

Exit codes: 0 success; 1 a solve stopped at --max-iter before reaching --tol
(every output is still written); 2 bad input, or not enough memory (a
one-line message on stderr, no traceback); 130 interrupted (SIGINT, Ctrl-C);
143 terminated (SIGTERM). The input file is only read. Every output is
written atomically: a temporary file in the same folder, fsync, then a
rename; an interrupted or terminated command leaves no temporary file (a
write under way finishes first).
"""

from __future__ import annotations

import codecs
import contextlib
import os
import signal
import sys
import threading
import warnings

from ..errors import SorpiaWarning
from . import progress as _progress
from .common import EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE, UserError, warn_once
from .parser import build_parser

__all__ = ["build_parser", "main"]


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc) or type(exc).__name__


class Terminated(BaseException):
    """SIGTERM (timeout, systemd, batch schedulers send it), raised as Python
    raises KeyboardInterrupt for SIGINT: the command unwinds the same way."""


@contextlib.contextmanager
def _sigterm_raises():
    """SIGTERM raises Terminated inside the block (once: a second SIGTERM while
    unwinding is ignored). Python runs the handler between bytecodes: during
    a call into the core it runs when the call returns, so a file being
    written is finished (or removed, if the write fails) first. Only the
    main thread can set a handler; elsewhere SIGTERM keeps its action."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_sigterm(signum, frame):
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise Terminated

    old = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old if old is not None else signal.SIG_DFL)


def _memory_text(exc: MemoryError) -> str:
    """One line for a MemoryError: the phase the command was in, numpy's words
    (what it could not allocate), the remedies; the core's std::bad_alloc
    arrives as MemoryError('std::bad_alloc'), which says nothing more."""
    phase = _progress.current_phase()
    detail = "" if str(exc) in ("", "std::bad_alloc") else f" ({exc})"
    return (f"not enough memory{detail}" + (f" while {phase}" if phase else "")
            + ": free memory, raise the limit (ulimit -v, the cgroup's memory limit) or give less work")


def _escape_undecodable(err: UnicodeError):
    """Error handler "sorpia.names": the bytes of a file name that are not
    UTF-8 (lone surrogates after os.fsdecode) printed as \\xNN, as the core's
    messages print them; any other character the stream cannot take as \\uNNNN."""
    if not isinstance(err, UnicodeEncodeError):
        raise err
    text = err.object[err.start:err.end]
    return "".join(f"\\x{ord(c) - 0xDC00:02x}" if 0xDC80 <= ord(c) <= 0xDCFF else f"\\u{ord(c):04x}"
                   for c in text), err.end


codecs.register_error("sorpia.names", _escape_undecodable)


@contextlib.contextmanager
def _printable_names():
    """stdout and stderr print any file name (see _escape_undecodable) inside the block."""
    streams = [(s, s.errors) for s in (sys.stdout, sys.stderr) if hasattr(s, "reconfigure")]
    for stream, _ in streams:
        with contextlib.suppress(ValueError, OSError):
            stream.reconfigure(errors="sorpia.names")
    try:
        yield
    finally:
        for stream, errors in streams:
            with contextlib.suppress(ValueError, OSError):  # closed meanwhile, or its reader left (the flush)
                stream.reconfigure(errors=errors)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `sorpia` script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)  # exits 2 with a usage line on a bad option
    if args.command is None:
        parser.print_help()
        return EXIT_OK

    def show(message, category, filename, lineno, file=None, line=None):
        warn_once(str(message))

    old_show = warnings.showwarning
    warnings.showwarning = show
    _progress.reset_phase()
    # Two levels: an interrupt can arrive while an error is being reported
    # (Ctrl-C during a read that then fails); the outer one catches it there too.
    try:
        with _sigterm_raises(), _printable_names(), warnings.catch_warnings():
            # sorpia's warnings are the command's to print (warn_once), whatever filter the caller set
            warnings.simplefilter("always", SorpiaWarning)
            try:
                return args.func(args)
            except UserError as exc:
                print(f"sorpia: error: {exc}", file=sys.stderr)
                return EXIT_USAGE
            except BrokenPipeError:
                # `sorpia info mesh.obj | head`: the reader left; not an error of ours.
                with contextlib.suppress(OSError):
                    sys.stdout = open(os.devnull, "w")
                return EXIT_OK
            except MemoryError as exc:  # std::bad_alloc from the core too
                print(f"sorpia: error: {_memory_text(exc)}", file=sys.stderr)
                return EXIT_USAGE
            except (ValueError, TypeError, OSError, ImportError) as exc:
                # sorpia.MeshError, ParameterError and MeshFileError are ValueErrors.
                print(f"sorpia: error: {_error_text(exc)}", file=sys.stderr)
                return EXIT_USAGE
    except KeyboardInterrupt:
        print("sorpia: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print("sorpia: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    finally:
        warnings.showwarning = old_show
