"""Benchmark pages for the documentation: docs/benchmarks/<slug>.md, stamped.

Every bench script writes its results through `write_page`, so a page says
which commit and which machine produced it and is regenerated, never edited by
hand. The stamp: the git commit (short hash, "+dirty" when the work tree has
uncommitted changes), the CPU model, cores, memory, operating system, the C++
compiler of the build tree when it can be found, the Python, numpy and scipy
versions, the load average when the page was written (other jobs on the
machine skew timings), the command line, and the UTC date.
"""

from __future__ import annotations

import datetime
import json
import os
import pathlib
import platform
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
PAGES_DIR = "docs/benchmarks"  # in the repository
PAGES = ROOT / PAGES_DIR


def _run(*cmd: str) -> str:
    """stdout of a command run in the repository, stripped; "" when it cannot run."""
    try:
        out = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""


def commit() -> str:
    """Short hash of HEAD, with "+dirty" when tracked files differ from it; "unknown" outside git.

    The pages and the README's excerpt are left out of the comparison: they are what the scripts write, so a
    run that regenerates several pages in turn stays clean.
    """
    head = _run("git", "rev-parse", "--short", "HEAD")
    if not head:
        return "unknown"
    dirty = _run("git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                 f":!{PAGES_DIR}", ":!README.md")
    return head + ("+dirty" if dirty else "")


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory() -> str:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemTotal:"):
                    return f"{int(line.split()[1]) / 2**20:.0f} GiB"
    except OSError:
        pass
    return "unknown"


def _os() -> str:
    name = platform.system()
    try:
        info = platform.freedesktop_os_release()
        name = info.get("PRETTY_NAME", name)
    except (OSError, AttributeError):
        pass
    return f"{name}, {platform.system()} {platform.release()}"


def _compiler() -> str:
    """The C++ compiler of the build tree the Makefile uses (its CMakeCache), else the c++ on PATH."""
    cxx = ""
    cache = ROOT / "build" / "python" / "CMakeCache.txt"
    if cache.exists():
        m = re.search(r"^CMAKE_CXX_COMPILER:\w+=(.+)$", cache.read_text(errors="replace"), re.M)
        cxx = m.group(1).strip() if m else ""
    version = _run(cxx or "c++", "--version")
    return version.splitlines()[0] if version else "unknown"


def machine() -> dict:
    """The machine a page was measured on."""
    out = {"cpu": _cpu_model(), "cores": os.cpu_count(), "memory": _memory(), "os": _os(),
           "compiler": _compiler(), "python": platform.python_version()}
    for mod in ("numpy", "scipy"):
        try:
            out[mod] = __import__(mod).__version__
        except ImportError:
            pass
    return out


def load_average() -> str:
    """The 1, 5 and 15 minute load averages, "1.0 / 0.9 / 0.8"; "unknown" where the system has none."""
    try:
        return " / ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def stamp() -> str:
    """The page's stamp as Markdown: commit, machine, command and date."""
    m = machine()
    libs = ", ".join(f"{k} {m[k]}" for k in ("python", "numpy", "scipy") if k in m)
    command = " ".join(["python", os.path.relpath(sys.argv[0], ROOT) if sys.argv[0] else "-"] + sys.argv[1:])
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"- commit: `{commit()}`\n"
            f"- machine: {m['cpu']}, {m['cores']} cores, {m['memory']} memory; {m['os']}\n"
            f"- compiler: {m['compiler']}; {libs}\n"
            f"- load average (1, 5, 15 min) when written: {load_average()}\n"
            f"- command: `{command}`\n"
            f"- date: {date}\n")


def write_page(slug: str, title: str, body_markdown: str, *, settings=None) -> pathlib.Path:
    """Write docs/benchmarks/<slug>.md: the title, the stamp, then the body; returns the path.

    slug: lowercase letters, digits, "-" and "_" (the file name). The page
    says it is generated, so that a change goes into the script, not the page.
    settings: the script's (argparse parser, parsed arguments), so that the
    page names the options run with other values than their defaults.
    """
    if not re.fullmatch(r"[a-z0-9][a-z0-9_-]*", slug):
        raise ValueError(f"page slug {slug!r}: use lowercase letters, digits, '-' and '_'")
    PAGES.mkdir(parents=True, exist_ok=True)
    path = PAGES / f"{slug}.md"
    script = os.path.relpath(sys.argv[0], ROOT) if sys.argv[0] else "a bench script"
    note = settings_note(*settings) if settings else ""
    note = note + "\n\n" if note else ""
    text = (f"# {title}\n\n"
            f"<!-- generated by {script} through bench/_report.py; rerun the script instead of editing -->\n\n"
            f"{stamp()}\n{note}{body_markdown.strip()}\n")
    path.write_text(text)
    print(f"page: {os.path.relpath(path)}", file=sys.stderr)
    return path


def write_readme_excerpt(name: str, slug: str, body_markdown: str) -> pathlib.Path:
    """Replace the README's excerpt `name` with body_markdown and a one-line stamp linking to page `slug`.

    The excerpt lies between the lines ``<!-- {name}: ... -->`` and ``<!-- end of {name} -->``; they stay, so
    the next run finds them. Raises ValueError when the README has no such markers.
    """
    readme = ROOT / "README.md"
    text = readme.read_text()
    m = re.search(rf"^<!-- {re.escape(name)}:.*?-->\n(.*?)^<!-- end of {re.escape(name)} -->$", text, re.M | re.S)
    if m is None:
        raise ValueError(f"README.md has no '<!-- {name}: ... -->' ... '<!-- end of {name} -->' markers")
    mach = machine()
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d")
    excerpt = (f"{body_markdown.strip()}\n\n"
               f"Measured at commit `{commit()}` on {mach['cpu']} ({mach['cores']} cores, {mach['memory']}), "
               f"{date}, load average {load_average()}; [the full page](docs/benchmarks/{slug}.md) gives the "
               "machine and the command.\n")
    readme.write_text(text[:m.start(1)] + excerpt + text[m.end(1):])
    print(f"README excerpt: {name}", file=sys.stderr)
    return readme


def print_json_plot(lines, rows, *, json_path, plot, no_page, default_plot, draw, caption) -> list:
    """A scaling script's ending: print the table `lines`, write `rows` to json_path (when given), draw the plot
    (`draw(rows, path)`, when there are two rows or more) at `plot`, or with a page at default_plot (beside it);
    returns the lines with the plot's image line added when the plot lies beside the pages."""
    print("\n".join(lines))
    if json_path:
        with open(json_path, "w") as fh:
            json.dump(rows, fh, indent=1)
    plot = plot or (None if no_page else str(default_plot))
    if len(rows) >= 2 and plot:
        os.makedirs(os.path.dirname(os.path.abspath(plot)), exist_ok=True)
        draw(rows, plot)
        if not no_page and os.path.dirname(os.path.abspath(plot)) == str(PAGES):
            lines = lines + ["", f"![{caption}]({os.path.basename(plot)})"]
    return lines


def settings_note(parser, args) -> str:
    """A Markdown line naming the options given other values than their defaults ("" when none were), so that
    a page run with smaller settings says so; options without a default (None) are left out."""
    changed = []
    for action in parser._actions:
        default = action.default
        if not action.option_strings or default is None or isinstance(default, bool) or default == "==SUPPRESS==":
            continue
        value = getattr(args, action.dest, default)
        if value != default:
            changed.append(f"`{action.option_strings[-1]} {value}` (default {default})")
    return "Settings other than the defaults: " + ", ".join(changed) + "." if changed else ""
