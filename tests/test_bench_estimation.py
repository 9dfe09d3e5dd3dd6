"""The estimation benchmark's rows, and what it says without OpenCV (timings are not asserted: a bench measures)."""

from __future__ import annotations

import sys

import pytest

from egtviz.bench.estimation import run_estimation_bench


def test_without_opencv_the_bench_says_so_and_gives_no_ratio(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "cv2", None)  # "import cv2" raises ImportError
    rows = run_estimation_bench(repeats=1)
    assert "OpenCV is not installed" in capsys.readouterr().out
    assert [r["case"].split(",")[0] for r in rows] == ["normalised 8-point", "RANSAC", "LMedS", "linear triangulation"]
    for r in rows:
        assert r["opencv_ms"] is None and r["ratio"] is None
        assert "OpenCV MISSING" in r["note"]
        assert r["ours_ms"] > 0.0


def test_with_opencv_every_row_has_a_ratio_and_the_robust_rows_an_accuracy():
    pytest.importorskip("cv2")
    rows = run_estimation_bench(repeats=1)
    for r in rows:
        assert r["ratio"] == pytest.approx(r["ours_ms"] / r["opencv_ms"])
    ransac = next(r for r in rows if r["case"].startswith("RANSAC"))
    assert "acc ours" in ransac["note"] and "OpenCV" in ransac["note"] and "target ratio <= 1.5" in ransac["note"]
