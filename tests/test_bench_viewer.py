"""The viewer benchmark's server half runs and reports sane figures (speed itself is not asserted)."""

from __future__ import annotations

import math

from egtviz.bench.viewer import _scenes, run_viewer_bench, server_latency


def test_server_rows_for_every_case():
    rows = run_viewer_bench(events=12, browser=False)
    cases = [r["case"] for r in rows]
    assert len(rows) == 8
    for pair in ("pin-hole", "panoramic"):
        for n in (8, 200):
            for q in ("p50", "p99"):
                assert f"viewer server, {pair} pair, {n} points, gizmo event ({q})" in cases
    for r in rows:
        assert math.isfinite(r["ours_ms"]) and r["ours_ms"] > 0, r
        assert "derived" in r["note"] and "SVG" in r["note"]


def test_each_event_is_a_real_update():
    scene = _scenes(8)["pin-hole"]
    s = server_latency(scene, 10, spacing=0.0)
    assert 0 < s["p50"] <= s["p99"]
    # Every event moved the camera, so every one ran the geometry and the panels.
    assert s["derived"] > 0 and s["svg"] > 0
