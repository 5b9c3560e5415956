"""`sorpia compare` run in-process: Table 1 and Figure 7 against the same
solves through the Python API."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

import sorpia
from sorpia.cli.common import DISPLAY_ORDER, METHOD_LABELS

TOLERANCE_HEADERS = [f"1e-{j}" for j in range(1, 11)]


def test_compare_writes_table_1_and_figure_7(torus_file, tmp_path, command):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    from matplotlib.image import imread

    src, V0, F = torus_file
    table, table_csv, js, plot = (tmp_path / n for n in ("t.md", "t.csv", "t.json", "p.png"))
    code, stdout, err = command("compare", src, "--table", table, "--csv", table_csv, "--json", js, "--plot", plot)
    assert code == 0, err
    md = table.read_text()
    assert md.strip() in stdout  # the printed table is the written one
    header = md.splitlines()[0]
    for tol in TOLERANCE_HEADERS:
        assert f"| {tol} |" in header
    assert set(DISPLAY_ORDER) == set(sorpia.solve.METHODS)  # every method of the library, no other
    for method in DISPLAY_ORDER:
        assert f"| {METHOD_LABELS[method]} |" in md

    rows = list(csv.DictReader(io.StringIO(table_csv.read_text())))
    assert [r["method"] for r in rows] == list(DISPLAY_ORDER)
    data = json.loads(js.read_text())
    # The Python API, same run: one Interpolator, every method solved on it, as compare does.
    interp = sorpia.Interpolator(F, len(V0))
    # The build is reported once, with the phases Interpolator reports, and is in no row.
    assert set(interp.build_timings) <= set(data["setup"])
    assert data["setup"]["wall_seconds"] >= 0 and data["setup"]["cpu_seconds"] >= 0
    assert "Not included: reading the file and the topology and limit operator" in stdout
    for row, entry in zip(rows, data["methods"]):
        ref = interp.solve(V0, method=entry["method"])
        assert entry["result"]["timings"]["topology"] == entry["result"]["timings"]["operator"] == 0
        assert entry["threads"] == 1 and entry["cpu_clock"] == "thread"
        assert entry["iterations"] == ref.iterations == int(row["iterations"])
        np.testing.assert_allclose(entry["history"], ref.history, rtol=1e-9, atol=1e-15)
        # iterations to reach 1e-j: the first k with E_k/E_0 < 1e-j, from the errors themselves
        errors = np.asarray(ref.history)
        for j, tol in enumerate(TOLERANCE_HEADERS, start=1):
            expected = int(np.flatnonzero(errors < 10.0 ** -j)[0])
            assert entry["reached"][j - 1] == expected == int(row[f"iterations_to_{tol}"])
    # The spectral estimates are shared: W-HSS (after HSS) needs H's extremes,
    # which HSS computed, so it spends no time estimating them again.
    timings = {e["method"]: e["result"]["timings"] for e in data["methods"]}
    assert timings["hss"]["estimate"] > 0 and timings["whss"]["estimate"] == 0
    image = imread(plot)
    assert image.shape[:2] == (560, 900)  # plotting.convergence_figure's default size
    assert image[..., :3].std() > 0.01  # not a blank image


def test_compare_not_converged_exits_1_with_dashes(torus_file, tmp_path, command):
    src, _, _ = torus_file
    table, table_csv = tmp_path / "t.md", tmp_path / "t.csv"
    code, stdout, err = command("compare", src, "--methods", "pia,sor", "--max-iter", 5, "--table", table,
                                "--csv", table_csv)
    assert code == 1, err
    assert "NOT converged" in stdout and "Traceback" not in err
    rows = list(csv.DictReader(io.StringIO(table_csv.read_text())))
    assert [r["converged"] for r in rows] == ["False", "False"]
    assert rows[0]["iterations_to_1e-10"] == ""  # not reached in 5 PIA steps
    pia_row = next(line for line in table.read_text().splitlines() if "| PIA |" in line)
    assert pia_row.rstrip().split("|")[-4].strip() == "-"  # the 1e-10 column
