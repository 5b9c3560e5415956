"""bench/_report.py, which stamps the benchmark pages: the page's layout, its stamp against git and /proc, and the
README excerpt it replaces. Nothing is timed here."""

import importlib.util
import os
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent


@pytest.fixture
def report(tmp_path, monkeypatch):
    """bench/_report.py loaded from the checkout, writing its pages and README into tmp_path."""
    spec = importlib.util.spec_from_file_location("_report", ROOT / "bench" / "_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    monkeypatch.setattr(module, "PAGES", tmp_path / "pages")
    return module


def git(*args):
    out = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
    return out.stdout.strip() if out.returncode == 0 else None


def test_page_has_title_stamp_and_body(report):
    path = report.write_page("demo-page", "A demo", "| a | b |\n|---|---|\n| 1 | 2 |\n")
    assert path == report.PAGES / "demo-page.md"
    text = path.read_text()
    assert text.startswith("# A demo\n")
    assert text.rstrip().endswith("| 1 | 2 |")
    stamp = dict(re.findall(r"^- ([a-z ()0-9,]+?): (.*)$", text, re.M))
    head = git("rev-parse", "--short", "HEAD")
    if head is not None:  # a checkout: the commit is HEAD's, with or without +dirty
        assert re.fullmatch(rf"`{head}(\+dirty)?`", stamp["commit"])
    assert f"{os.cpu_count()} cores" in stamp["machine"]
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", stamp["date"])


@pytest.mark.parametrize("slug", ["", "Upper", "a/b", "../x", "a b"])
def test_page_slug_must_be_a_plain_file_name(report, slug):
    with pytest.raises(ValueError, match="slug"):
        report.write_page(slug, "t", "body")


def test_readme_excerpt_replaces_only_between_its_markers(report, tmp_path, monkeypatch):
    readme = tmp_path / "README.md"
    before = "# x\n\n<!-- t: generated -->\nold table\n<!-- end of t -->\n\ntail\n"
    readme.write_text(before)
    monkeypatch.setattr(report, "ROOT", tmp_path)
    report.write_readme_excerpt("t", "slug", "new table")
    text = readme.read_text()
    assert text.startswith("# x\n\n<!-- t: generated -->\nnew table\n")
    assert "old table" not in text
    assert text.endswith("<!-- end of t -->\n\ntail\n")
    assert "docs/benchmarks/slug.md" in text
    report.write_readme_excerpt("t", "slug", "newer table")  # the markers stay for the next run
    assert "newer table" in readme.read_text() and "new table\n" not in readme.read_text()


def test_readme_without_markers_is_refused(report, tmp_path, monkeypatch):
    (tmp_path / "README.md").write_text("# x\n")
    monkeypatch.setattr(report, "ROOT", tmp_path)
    with pytest.raises(ValueError, match="markers"):
        report.write_readme_excerpt("t", "slug", "table")


def test_page_names_the_options_that_differ_from_their_defaults(report):
    import argparse

    parser = argparse.ArgumentParser()
    parser.add_argument("mesh")
    parser.add_argument("--sizes", default="10,100,1000")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", default=None)
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args(["m.ply", "--sizes", "10,100", "--json", "x.json"])
    text = report.write_page("p", "t", "body", settings=(parser, args)).read_text()
    notes = [line for line in text.splitlines() if line.startswith("Settings other than the defaults")]
    assert notes == ["Settings other than the defaults: `--sizes 10,100` (default 10,100,1000)."]
    args = parser.parse_args(["m.ply"])
    assert "Settings other" not in report.write_page("p", "t", "body", settings=(parser, args)).read_text()
