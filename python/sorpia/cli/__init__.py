"""The ``sorpia`` command (also ``python -m sorpia``).

Subcommands, one module each: ``fit`` (control mesh whose Loop limit surface
interpolates a mesh file), ``compare`` (the paper's Table 1 and Figure 7 for
one mesh), ``render`` (the paper's Figure 3), ``info`` (mesh statistics, the
paper's Table 2) and ``demo`` (all of it on a generated sample mesh);
``parser`` holds their options, ``output`` the files they write besides
meshes, ``progress`` the progress line, ``common`` what they share.

Exit codes: 0 success; 1 a solve stopped at --max-iter before reaching --tol
(every output is still written); 2 bad input (a one-line message on stderr, no
traceback); 130 interrupted. The input file is only read. Every output is
written atomically: a temporary file in the same folder, fsync, then a rename.
"""

from __future__ import annotations

import contextlib
import os
import sys
import warnings

from .common import EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, UserError, warn_once
from .parser import build_parser

__all__ = ["build_parser", "main"]


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc) or type(exc).__name__


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
    except (ValueError, TypeError, OSError, ImportError) as exc:
        # sorpia.MeshError, ParameterError and MeshFileError are ValueErrors.
        print(f"sorpia: error: {_error_text(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("sorpia: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        warnings.showwarning = old_show
