"""Mistakes that mypy must report (tests/test_typing.py): proof that it reads sorpia's types and does not take
them as Any. Each line with an error comment is one that mypy must flag; the test checks the line numbers."""

from __future__ import annotations

import sorpia

V, F = sorpia.shapes.icosphere("2")  # error: a str for the level
res = sorpia.interpolate(V, F, tol="small")  # error: a str for tol
print(res.control_vertice)  # error: no such attribute
count: str = res.iterations  # error: an int is not a str
