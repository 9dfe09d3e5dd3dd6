"""``egtviz bench classroom --json FILE``: the figures of each tab count beside the bare-viser floor at the same
rate, as strict JSON (speed itself is not asserted)."""

from __future__ import annotations

import json
import math

import pytest

from egtviz.bench import classroom
from egtviz.bench.classroom import ClassroomRun, classroom_record
from egtviz.bench.viser_floor import FloorRun
from egtviz.cli import main


def _run(tabs: int, applied: int, cpu_s: float) -> ClassroomRun:
    return ClassroomRun(tabs=tabs, seconds=2.0, sent=40 * tabs, applied=applied, cpu_s=cpu_s, wall_s=2.5,
                        parts_ms={"geometry": 0.5, "svg": 1.5}, lag_ms=(12.0, 40.0), unserved=0,
                        rss_per_tab_mb=1.0, tabs_cpu_s=0.5, received_mb=0.3)


def test_record_pairs_each_run_with_its_floor_and_ratio():
    runs = [_run(1, 40, 0.12), _run(5, 150, 0.6)]
    floors = [FloorRun(20.0, 40, 40, 0.04), FloorRun(100.0, 200, 200, 0.3)]
    rec = classroom_record(runs, floors, scene=None, points=200, areas=[("numpy", 0.3), ("svg", 0.1)],
                           profiled=runs[1])
    one, five = rec["runs"]
    assert (one["tabs"], one["rate_hz"], five["rate_hz"]) == (1, 20.0, 100.0)
    assert one["cpu_ms_per_update"] == pytest.approx(3.0) and one["floor_ms_per_update"] == pytest.approx(1.0)
    assert one["ratio_to_floor"] == pytest.approx(3.0)
    assert five["cpu_ms_per_update"] == pytest.approx(4.0) and five["floor_ms_per_update"] == pytest.approx(1.5)
    assert five["ratio_to_floor"] == pytest.approx(4.0 / 1.5)
    assert one["parts_ms"] == {"geometry": 0.5, "svg": 1.5}
    assert one["lag_ms"] == {"p50": 12.0, "p99": 40.0} and one["unserved"] == 0
    assert (rec["scene"], rec["points"]) == ("default", 200)
    assert [a["area"] for a in rec["profile"]["areas"]] == ["numpy", "svg"]
    assert rec["profile"]["areas"][0]["share"] == pytest.approx(0.75)
    assert rec["profile"]["areas"][0]["ms_per_update"] == pytest.approx(2.0)  # 0.3 s over 150 updates


def test_record_refuses_a_floor_missing_for_a_run():
    with pytest.raises(ValueError):
        classroom_record([_run(1, 40, 0.1)], [], scene=None, points=None)


def test_a_run_with_nothing_applied_is_written_as_null_not_nan(tmp_path, monkeypatch):
    runs = iter([_run(1, 0, 0.1)])
    monkeypatch.setattr(classroom, "run_classroom", lambda *a, **k: (next(runs), None))
    monkeypatch.setattr("egtviz.bench.viser_floor.viser_floor", lambda rate, seconds: FloorRun(rate, 5, 0, 0.01))
    out = tmp_path / "c.json"
    text = classroom.run_classroom_bench((1,), seconds=1.0, profile=False, json_path=str(out))
    assert "ratio to the floor" in text
    rec = json.loads(out.read_text())  # strict: a NaN would be refused by allow_nan=False when written
    assert rec["runs"][0]["cpu_ms_per_update"] is None and rec["runs"][0]["floor_ms_per_update"] is None


def test_other_suites_refuse_the_classroom_options(capsys):
    assert main(["bench", "core", "--json", "x.json"]) == 2
    assert "classroom suite only" in capsys.readouterr().err


def test_a_short_real_classroom_writes_its_figures(tmp_path):
    out = tmp_path / "classroom.json"
    classroom.run_classroom_bench((1,), seconds=1.0, profile=False, json_path=str(out), points=12)
    rec = json.loads(out.read_text())
    (row,) = rec["runs"]
    assert rec["points"] == 12 and row["tabs"] == 1 and row["rate_hz"] == 20.0
    assert row["sent"] == 20 and 0 < row["applied"] <= 21
    assert row["floor_callbacks"] > 0 and row["floor_ms_per_update"] > 0
    assert row["cpu_ms_per_update"] > 0
    assert math.isclose(row["ratio_to_floor"], row["cpu_ms_per_update"] / row["floor_ms_per_update"])
    assert math.isclose(sum(row["parts_ms"].values()), row["cpu_ms_per_update"], rel_tol=1e-6)
    assert row["lag_ms"]["p50"] <= row["lag_ms"]["p99"] and row["unserved"] == 0


# -- the end of a drag: a tab waiting its turn is not counted as unanswered -------------------------------------


def _frame(rev: int) -> bytes:
    import zstandard

    body = f'<svg data-egtviz="image-plane" data-camera="cam1" data-rev="{rev}">'.encode()
    packed = zstandard.ZstdCompressor().compress(body)
    return len(body).to_bytes(8, "little") + len(packed).to_bytes(8, "little") + packed


class _SlowServer:
    """A tab's socket on a saturated server: panels at ``times`` seconds after the drag's start (a fixed schedule:
    the listener cancels a receive after 0.1 s), the last one after the drag ended."""

    def __init__(self, times: list[float]) -> None:
        self.ws = self
        self.sent: list[dict] = []
        self._times = times
        self._due: list[float] = []
        self._rev = 0

    async def send(self, message: dict) -> None:
        import time

        if not self.sent:
            self._due = [time.monotonic() + t for t in self._times]
        self.sent.append(message)

    async def recv(self) -> bytes:
        import asyncio
        import time

        if not self._due or self._rev == len(self._due):
            await asyncio.sleep(3600)
        await asyncio.sleep(max(0.0, self._due[self._rev] - time.monotonic()))
        self._rev += 1
        return _frame(self._rev)


def test_a_tab_waits_for_its_turn_before_counting_updates_unanswered():
    import asyncio
    import time

    # Two updates in 0.1 s; the panels 0.6 s apart (longer than QUIET_S), the last two after the drag ended.
    client = _SlowServer([0.45, 1.05, 1.65])
    pose = {"position": [0.0, 0.0, 0.0], "wxyz": [1.0, 0.0, 0.0, 0.0], "owner": 1}
    out = asyncio.run(classroom._drag_and_listen(client, pose, 0, 1, seconds=0.2, rate=10.0, t0=time.time()))
    assert classroom.QUIET_S < 0.6
    assert [rev for rev, _ in out["panels"]] == [1, 2, 3]  # the listener stayed for the last one
    assert [m["type"] for m in client.sent][-1] == "TransformControlsDragEndMessage"
