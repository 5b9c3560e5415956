"""The ``sorpia-cli`` directive: the command-line reference, generated from ``sorpia.cli.build_parser()``.

One section per command, each holding the command's own ``--help`` text as a literal block, so the page says
exactly what ``sorpia COMMAND --help`` prints and cannot drift from it. The help is rendered at a fixed width
(COLUMNS), so the page does not depend on the terminal that builds it.
"""

from __future__ import annotations

import argparse
import os

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

WIDTH = "100"


def _help(parser: argparse.ArgumentParser) -> str:
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        return parser.format_help()
    finally:
        if saved is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = saved


def commands(parser: argparse.ArgumentParser):
    """[(name, subparser)] in the order the parser defines them."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices.items())
    return []


class SorpiaCli(SphinxDirective):
    """``.. sorpia-cli::`` with an optional title adornment character for the command sections (default -)."""

    optional_arguments = 1

    def run(self):
        from sorpia.cli import build_parser

        mark = self.arguments[0] if self.arguments else "-"
        parser = build_parser()
        lines = []

        def block(title, text):
            head = f"``{title}``"
            lines.extend([head, mark * len(head), "", ".. code-block:: text", ""])
            lines.extend("   " + line if line else "" for line in text.rstrip().splitlines())
            lines.append("")

        block(parser.prog, _help(parser))
        for name, sub in commands(parser):
            block(f"{parser.prog} {name}", _help(sub))
        node = nodes.section()
        node.document = self.state.document
        nested_parse_with_titles(self.state, StringList(lines, source="sorpia.cli.build_parser"), node)
        return node.children


def setup(app):
    app.add_directive("sorpia-cli", SorpiaCli)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
