"""`sorpia render` run in-process: the paper's Figure 3 as a PNG."""

from __future__ import annotations

import pytest

pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")


def test_render_draws_figure_3(torus_file, tmp_path, command):
    from matplotlib.image import imread

    src, _, _ = torus_file
    fig = tmp_path / "fig3.png"
    code, _, err = command("render", src, "-o", fig, "--level", 1, "--size", "640x480")
    assert code == 0, err
    image = imread(fig)
    assert image.shape[:2] == (480, 640)
    rgb = image[..., :3]
    red = (rgb[..., 0] > 0.7) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)
    blue = (rgb[..., 2] > 0.6) & (rgb[..., 0] < 0.3)
    assert red.sum() > 50 and blue.sum() > 20  # the given (red) and control (blue) vertices are drawn
