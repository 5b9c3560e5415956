"""Benchmark pages of the docs: docs/benchmarks/<slug>.md, written by the bench
scripts, stamped with the commit and the machine they ran on."""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.strip()
        # The pages and figures the bench scripts write are not changes to what was measured.
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":!docs/benchmarks", ":!bench/*.json"], cwd=ROOT, capture_output=True,
                               text=True).stdout.strip()
        return out + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, Python {platform.python_version()}"


def write_page(slug: str, title: str, body_markdown: str) -> Path:
    """Write docs/benchmarks/<slug>.md: the title, the commit and machine, then the body."""
    path = ROOT / "docs" / "benchmarks" / f"{slug}.md"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"# {title}\n\nCommit {_commit()}; machine: {_machine()}.\n\n{body_markdown.rstrip()}\n")
    return path
