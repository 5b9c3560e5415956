"""The ``sorpia`` command (also ``python -m sorpia``)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from . import __version__


def _cmd_demo(args: argparse.Namespace) -> int:
    from . import limit_points, shapes

    vertices, faces = shapes.irregular(args.vertices, seed=1)
    limit = limit_points(vertices, faces)
    shrink = np.linalg.norm(limit - vertices, axis=1)
    diag = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    print(f"sorpia {__version__} demo: generated irregular closed mesh, "
          f"{len(vertices)} vertices, {len(faces)} faces")
    print(f"Loop limit points (OpenSubdiv): |limit - vertex| mean {shrink.mean():.4g}, "
          f"max {shrink.max():.4g} ({100 * shrink.max() / diag:.2f}% of the bounding-box diagonal)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sorpia",
        description="Interpolating Loop subdivision surfaces: move the control vertices of a triangle mesh "
        "so that its Loop limit surface passes through the given vertices (SOR-PIA and the PIA family).",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"sorpia {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser("demo", help="run the main job on a built-in sample mesh",
                          formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    demo.add_argument("--vertices", type=int, default=400, help="size of the generated sample mesh")
    demo.set_defaults(func=_cmd_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
