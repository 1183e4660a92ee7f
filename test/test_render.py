"""Figures drawn beside the computation (susp_sim_ros/analysis/render.py): every submitted figure is
written when the block ends, in a child or by the caller, and a failed one is named in an error."""
import os

import pytest

from susp_sim_ros.analysis.render import FigureRenderer


def _draw(path, text):
    with open(path, "w") as fh:
        fh.write(f"{text} {os.getpid()}")


def _fail(path):
    raise ValueError(f"cannot draw {path}")


@pytest.mark.parametrize("parallel", [True, False])
def test_every_figure_is_written_when_the_block_ends(tmp_path, parallel):
    paths = [tmp_path / f"f{k}.txt" for k in range(7)]
    with FigureRenderer(parallel=parallel) as r:
        for p in paths[:3]:
            r.submit(str(p), _draw, p, "early")
        r.flush()
        for p in paths[3:]:
            r.submit(str(p), _draw, p, "late")
    assert all(p.read_text().split()[0] in ("early", "late") for p in paths)
    pids = {p.read_text().split()[1] for p in paths}
    if not parallel:
        assert pids == {str(os.getpid())}


def test_a_figure_that_fails_is_named(tmp_path):
    good, bad = tmp_path / "good.txt", tmp_path / "bad.png"
    r = FigureRenderer()
    r.submit(str(bad), _fail, bad)
    r.flush()
    r.submit(str(good), _draw, good, "x")
    with pytest.raises((RuntimeError, ValueError), match="bad.png"):
        r.wait()
    assert good.exists()


def _draw_slowly(path, text, seconds):
    import time
    time.sleep(seconds)
    _draw(path, text)


@pytest.mark.skipif(FigureRenderer()._spare == 0 or FigureRenderer()._ctx is None,
                    reason="no spare core or no fork: figures are drawn in place")
def test_a_child_that_comes_free_takes_part_of_what_is_left(tmp_path):
    """The early figures' child finishes while the caller draws the late ones: it takes half of what is
    left (was: the caller drew every late figure alone while the child stood idle)."""
    early, late = tmp_path / "early.txt", [tmp_path / f"late{k}.txt" for k in range(6)]
    with FigureRenderer() as r:
        r.submit(str(early), _draw_slowly, early, "early", 0.3)
        r.flush()
        for p in late:
            r.submit(str(p), _draw_slowly, p, "late", 0.2)
    pids = {p.read_text().split()[1] for p in late}
    assert str(os.getpid()) in pids and len(pids) > 1
