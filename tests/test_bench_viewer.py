"""The viewer benchmarks run and report sane figures (speed itself is not asserted): the server's latency,
its CPU per drag update, and the classroom (many raw websocket tabs on one server)."""

from __future__ import annotations

import cProfile
import math

import msgspec.msgpack
import numpy as np
import pytest
import zstandard

from egtviz.bench import classroom
from egtviz.bench.classroom import STEP_M, run_classroom
from egtviz.bench.viewer import _scenes, run_viewer_bench, server_latency
from egtviz.bench.ws_client import decode_frame, frame_payload


def test_server_rows_for_every_case():
    rows = run_viewer_bench(events=12, browser=False, cpu_seconds=1.0)
    cases = [r["case"] for r in rows]
    assert len(rows) == 3 + 4 * 2 * 2
    for scene in ("pin-hole pair", "panoramic pair", "4 cameras", "unified pair"):
        for n in (8, 200):
            for q in ("p50", "p99"):
                assert f"viewer server, {scene}, {n} points, gizmo event ({q})" in cases
    cpu = [r for r in rows if "CPU per drag update" in r["case"]]
    assert [r["case"].split(",")[1].split("(")[0].strip() for r in cpu] == ["pin-hole pair", "panoramic pair",
                                                                            "the floor: bare viser"]
    # The floor: 5 tabs' worth of updates a second for one second, every one received.
    assert cpu[2]["case"].endswith("100 updates/s") and cpu[2]["note"].startswith("100 of 100 received")
    for r in rows:
        assert math.isfinite(r["ours_ms"]) and r["ours_ms"] > 0, r
    for r in rows:
        if r is cpu[2]:
            continue
        if r in cpu:
            assert "updates applied" in r["note"] and "geometry" in r["note"] and "svg" in r["note"]
        else:
            assert "derived" in r["note"] and "SVG" in r["note"]


def test_the_bench_scenes_are_the_ones_named():
    scenes = _scenes(8)
    kinds = {label: [c.model_kind for c in s.cameras] for label, s in scenes.items()}
    assert kinds == {"pin-hole": ["pinhole", "pinhole"], "panoramic": ["hyperbolic", "hyperbolic"],
                     "4 cameras": ["pinhole", "pinhole", "pinhole", "unified"], "unified": ["pinhole", "unified"]}
    assert scenes["unified"].drawn_pair == ("cam1", "uni1")
    assert all(len(s.points) == 8 for s in scenes.values())


def test_each_event_is_a_real_update():
    scene = _scenes(8)["pin-hole"]
    s = server_latency(scene, 10, spacing=0.0)
    assert 0 < s["p50"] <= s["p99"]
    # Every event moved the camera, so every one ran the geometry and the panels.
    assert s["derived"] > 0 and s["svg"] > 0


# -- the classroom ---------------------------------------------------------------------------------------------


def test_classroom_run_measures_every_update_of_every_tab():
    run, stats = run_classroom(2, seconds=1.5)
    assert stats is None
    assert run.sent == 2 * 30  # 20 Hz for 1.5 s, per tab
    # Merged updates are drawn once; a drag end that moved nothing redraws once per tab.
    assert 0 < run.applied <= run.sent + 2
    assert run.unserved == 0  # two tabs never saturate the server: every update got a panel
    p50, p99 = run.lag_ms
    assert 0 < p50 <= p99 < 5000
    # The parts are the whole: they add up to the CPU per update, and the drawing stages all ran.
    assert sum(run.parts_ms.values()) == pytest.approx(run.cpu_ms_per_update, rel=1e-9)
    for stage in ("geometry", "svg", "scene3d", "viser dispatch+send"):
        assert run.parts_ms[stage] > 0, stage
    assert run.cpu_ms_per_update == pytest.approx(1e3 * run.cpu_s / run.applied)
    assert math.isfinite(run.rss_per_tab_mb) and run.received_mb > 0


def test_classroom_profile_splits_the_time_by_area():
    run, stats = run_classroom(1, seconds=1.0, profile=True)
    areas = dict(classroom.profile_areas(stats))
    assert run.applied > 0
    # The update path's own code shows up where it belongs (geometry, the SVG, the 3D nodes, viser).
    for area in ("geometry (egtviz.geometry)", "SVG: the rest (egtviz.viewer.render.svg)",
                 "3D nodes (egtviz.viewer.workbench.scene3d, models)", "viser messages + transport (infra)"):
        assert areas.get(area, 0.0) > 0, (area, areas)


def test_lags_take_the_first_panel_drawn_from_that_update_or_a_later_one():
    start = (-3.0, -8.0, 1.5)
    j = 1  # the tab's updates are at y = y0 + (j + 1) mm

    def pose(k: int, tab: int = j) -> tuple[float, float, float]:
        return (start[0] + STEP_M * (k + 1), start[1] + STEP_M * (tab + 1), start[2])

    # Revision 5 drew update 1, revision 6 update 3 (2 was merged into 3); revision 7 is another tab's.
    drawn = [(5, pose(1)), (6, pose(3)), (7, pose(4, tab=0))]
    tab = {"sends": [(0, 0.0), (1, 1.0), (2, 2.0), (3, 3.0), (4, 4.0)],
           "panels": [(5, 1.5), (6, 3.2), (7, 4.1)]}
    lags, unserved = classroom._lags(tab, drawn, start, j)
    # By hand: 0 and 1 are answered by revision 5 at 1.5 s, 2 and 3 by revision 6 at 3.2 s, 4 by nothing
    # (revision 7 drew the other tab's update).
    np.testing.assert_allclose(lags, [1.5, 0.5, 1.2, 0.2])
    assert unserved == 1


def test_parts_split_the_process_time_without_losing_any():
    stages = {"callback": 0.9, "render": 0.6, "geometry": 0.2, "svg": 0.25, "fields": 0.05, "scene3d": 0.1,
              "flush": 0.02}
    parts = classroom._parts(stages, cpu_s=1.5, applied=100)
    # By hand, ms per update: model = (0.9 - 0.6 - 0.2) / 100 s, panels = (0.6 - 0.25 - 0.05 - 0.1 - 0.02) / 100 s.
    assert parts["model"] == pytest.approx(1.0)
    assert parts["panels+readout"] == pytest.approx(1.8)
    assert parts["viser dispatch+send"] == pytest.approx(6.0)
    assert sum(parts.values()) == pytest.approx(15.0)


def test_profile_areas_give_c_functions_to_their_callers():
    from egtviz.viewer.render.panel_view import place_labels

    rng = np.random.default_rng(3)
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(20):
        place_labels(rng.uniform(0, 640, (12, 2)), np.full(12, 4.0), np.full((12, 2), 20.0),
                     rng.uniform(0, 640, (30, 4)), (0, 0, 640, 480), 2.0)
    prof.disable()
    import pstats

    stats = pstats.Stats(prof)
    areas = dict(classroom.profile_areas(stats))
    # C functions (numpy methods, list building) that only place_labels called: their time is the caller's.
    c_time = sum(v[2] for (path, _l, _name), v in stats.stats.items()
                 if path == "~" and v[4] and all(c[0].endswith("egtviz/viewer/render/panel_view.py") for c in v[4]))
    assert c_time > 0
    own = sum(v[2] for (path, _l, _name), v in stats.stats.items() if path.endswith("egtviz/viewer/render/panel_view.py"))
    assert areas["SVG: label placement (egtviz.viewer.render.panel_view)"] > own  # its own time and its C calls' time
    assert sum(areas.values()) == pytest.approx(sum(v[2] for v in stats.stats.values()), rel=1e-9)


def test_run_classroom_names_a_bad_argument():
    with pytest.raises(ValueError, match="tabs: expected a positive integer"):
        run_classroom(0)
    with pytest.raises(ValueError, match="seconds, rate"):
        run_classroom(1, seconds=0.0)


# -- the raw client's frames -------------------------------------------------------------------------------------


def _frame(messages: list[dict]) -> bytes:
    """A server frame laid out as viser's infra writes it: sizes (8 B each, little-endian), then zstd msgpack."""
    raw = msgspec.msgpack.encode({"messages": messages})
    packed = zstandard.ZstdCompressor().compress(raw)
    return len(raw).to_bytes(8, "little") + len(packed).to_bytes(8, "little") + packed


def test_decode_frame_reads_what_viser_writes():
    msgs = [{"type": "GuiUpdateMessage", "uuid": "u", "updates": {"content": "<svg/>"}}, {"type": "X"}]
    assert decode_frame(_frame(msgs)) == msgs
    assert b"<svg/>" in frame_payload(_frame(msgs))


def test_frame_payload_refuses_a_truncated_frame():
    with pytest.raises(ValueError, match="frame: expected at least 16 bytes"):
        frame_payload(b"\0" * 10)
    with pytest.raises(ValueError, match="frame: declares"):
        frame_payload(_frame([{"type": "X"}])[:-3])
