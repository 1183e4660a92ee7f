"""Progress: a bar on a terminal, plain periodic lines where nobody watches, nothing when switched off;
one helper used by every long command."""
from __future__ import annotations

import io
import re
from pathlib import Path

import pytest

from susp_sim_ros.errors import SuspInputError
from susp_sim_ros.progress import PlainProgress, progress

ROOT = Path(__file__).resolve().parents[1]


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture(autouse=True)
def auto_mode(monkeypatch):
    monkeypatch.delenv("SUSP_PROGRESS", raising=False)


def test_terminal_gets_a_bar():
    out = Terminal()
    with progress(total=5, desc="study", unit="run", stream=out, mininterval=0) as bar:
        for _ in range(5):
            bar.update()
    text = out.getvalue()
    assert "\r" in text and "study" in text and "5/5" in text


def test_log_gets_plain_lines_at_most_every_interval():
    out, clock = io.StringIO(), Clock()
    bar = PlainProgress(total=100, desc="study", unit="run", stream=out, interval_s=10.0, clock=clock)
    for k in range(100):
        clock.t = 0.5 * k       # 50 s in all: a line at 10, 20, 30, 40 s
        bar.update()
    clock.t = 50.0
    bar.close()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    assert len(lines) == 5, lines
    assert lines[0] == "study: 21/100 run (21 %), 10 s, about 38 s left"  # 21 runs done in 10 s
    assert lines[-1] == "study: 100/100 run (100 %), 50 s, done"


def test_short_run_in_a_log_writes_nothing():
    out, clock = io.StringIO(), Clock()
    with PlainProgress(total=3, desc="paper study", stream=out, clock=clock) as bar:
        for _ in range(3):
            clock.t += 1.0
            bar.update()
    assert out.getvalue() == ""


def test_without_total_and_with_postfix_and_resume():
    out, clock = io.StringIO(), Clock()
    bar = PlainProgress(desc="diagnose: vehicle runs", unit="run", stream=out, interval_s=1.0, clock=clock)
    clock.t = 2.0
    bar.set_postfix_str("drive_a.mcap")
    bar.update(64)
    assert out.getvalue() == "diagnose: vehicle runs: 64 run, 2 s [drive_a.mcap]\n"
    out2 = io.StringIO()
    resumed = PlainProgress(total=10, initial=4, desc="x", unit="chunk", stream=out2, interval_s=1.0, clock=clock)
    clock.t = 5.0
    resumed.update(2)   # 2 chunks in 3 s since the resume: 4 left take about 6 s
    assert out2.getvalue() == "x: 6/10 chunk (60 %), 3 s, about 6 s left\n"


def test_progress_picks_by_isatty_and_the_environment(monkeypatch):
    from tqdm import tqdm
    assert isinstance(progress(total=1, stream=Terminal()), tqdm)
    assert isinstance(progress(total=1, stream=io.StringIO()), PlainProgress)
    off = progress(total=1, stream=io.StringIO(), enabled=False)
    assert isinstance(off, PlainProgress) and not off.enabled
    monkeypatch.setenv("SUSP_PROGRESS", "lines")
    assert isinstance(progress(total=1, stream=Terminal()), PlainProgress)
    monkeypatch.setenv("SUSP_PROGRESS", "bar")
    assert isinstance(progress(total=1, stream=io.StringIO()), tqdm)
    monkeypatch.setenv("SUSP_PROGRESS", "off")
    quiet = progress(total=1, stream=Terminal(), interval_s=0.0)
    quiet.update()
    quiet.close()
    assert not quiet.enabled
    monkeypatch.setenv("SUSP_PROGRESS", "sometimes")
    with pytest.raises(SuspInputError, match="SUSP_PROGRESS='sometimes'"):
        progress(total=1)


def test_disabled_progress_writes_nothing_even_when_slow():
    out, clock = io.StringIO(), Clock()
    bar = PlainProgress(total=10, stream=out, interval_s=1.0, clock=clock, enabled=False)
    for _ in range(10):
        clock.t += 5.0
        bar.update()
    bar.close()
    assert out.getvalue() == ""


def test_one_helper_everywhere():
    """No module but susp_sim_ros/progress.py makes its own tqdm bar or rewrites a line with a carriage
    return."""
    offenders = []
    for p in (ROOT / "susp_sim_ros").rglob("*.py"):
        if p.name == "progress.py":
            continue
        text = p.read_text()
        if re.search(r"\btqdm\b", text) or re.search(r"""end\s*=\s*['"]\\r['"]|print\(['"]\\r""", text):
            offenders.append(str(p.relative_to(ROOT)))
    assert offenders == []


def test_paper_command_in_a_log_has_no_bar(tmp_path, monkeypatch, capsys):
    """A long command with stderr not a terminal (here: captured): no carriage returns, and with a
    zero interval, plain lines that count the runs."""
    import susp_sim_ros.progress as P
    from susp_sim_ros.cli.main import main
    monkeypatch.setattr(P, "LINE_INTERVAL_S", 0.0)
    monkeypatch.setattr(P.progress, "__kwdefaults__", {**P.progress.__kwdefaults__, "interval_s": 0.0})
    rc = main(["paper", "--out", str(tmp_path / "paper"), "--json"])
    err = capsys.readouterr().err
    assert rc == 0
    assert "\r" not in err
    assert re.search(r"^paper study: 1/24 run \(4 %\)", err, re.M) and "paper study: 24/24 run (100 %)" in err
