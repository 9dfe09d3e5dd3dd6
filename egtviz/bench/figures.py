"""``egtviz bench figures``: EGT's plotting at many points, and a loop of drawings with browser tabs open.

Each case is timed once (the slow cases of before took seconds to minutes; one run shows the order). The plot
cases state their time as a ratio to the projection alone; the drawing loop as a ratio to the same loop with no
tab open, timed in the same run.
"""

from __future__ import annotations

import os
import time
import warnings
from typing import Any

import numpy as np

__all__ = ["run_figures_bench"]

#: Drawing calls in the loop case (a script drawing a frame per step of an animation).
LOOP_CALLS = 300


def _timed(fn, *args) -> float:
    start = time.perf_counter()
    fn(*args)
    return (time.perf_counter() - start) * 1e3


def _plot_rows() -> list[dict[str, Any]]:
    import egtviz.egt_figure as ef
    from egtviz.egt import eye, f_epipline, f_epipole, f_perspproj, f_Rt2H, rotoz

    rng = np.random.default_rng(0)
    K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
    H1, H2 = f_Rt2H(rotoz(0.3), [-1.0, -5.0, 0.0]), f_Rt2H(eye(3), [0.0, -5.0, 0.0])
    rows = []
    for n in (1_000, 10_000, 1_000_000):
        P = rng.uniform(-1.0, 1.0, (3, n)) + np.array([[0.0], [5.0], [0.0]])
        ef.reset()
        alone = _timed(f_perspproj, P, H2, K)
        plotted = _timed(f_perspproj, P, H2, K, 1)
        drawn = "drawn" if ef.current_figure().annotations().plots else "refused (over the 2,000 of a plot)"
        rows.append(dict(case=f"f_perspproj with plot, {n:,} points", ours_ms=plotted,
                         ratio=plotted / alone, note=f"ratio: to the projection alone; {drawn}"))
    P = rng.uniform(-1.0, 1.0, (3, 6_000)) + np.array([[0.0], [5.0], [0.0]])
    U1, U2 = f_perspproj(P, H1, K), f_perspproj(P, H2, K)
    _, _, F = f_epipole(H1, H2, K, K)
    ef.reset()
    alone = _timed(f_epipline, U1, U2, F)
    plotted = _timed(f_epipline, U1, U2, F, 1, 1, 2)
    rows.append(dict(case="f_epipline with plot, 6,000 points", ours_ms=plotted, ratio=plotted / alone,
                     note="ratio: to the lines alone; refused (over the 2,000 of a plot)"))
    return rows


def _loop_row(tabs: int, baseline_ms: float | None) -> dict[str, Any]:
    """``LOOP_CALLS`` calls of ``f_3Dframe`` with ``tabs`` headless tabs open on the figure server."""
    import egtviz.egt_figure as ef
    from egtviz.egt import f_3Dframe, f_Rt2H, rotoz
    from egtviz.viewer.server.headless import FakeTab

    ef.reset()
    ef.figure(1)
    server = ef.figure_server()
    assert server is not None
    fakes = [FakeTab(server.server.get_port()) for _ in range(tabs)]
    try:
        views = server.app.wait_for_view(count=tabs, timeout=60) if tabs else []
        ef.flush()
        loads = [0] * len(views)
        for i, view in enumerate(views):
            def counted(scene, _i=i, _load=view.model.load_scene):
                loads[_i] += 1
                return _load(scene)

            view.model.load_scene = counted
        start = time.perf_counter()
        for k in range(LOOP_CALLS):
            f_3Dframe(f_Rt2H(rotoz(0.01 * k), [0.01 * k, 0.0, 0.0]), "r", 0.5)
        calls_ms = (time.perf_counter() - start) * 1e3
        ef.flush()
        current_ms = (time.perf_counter() - start) * 1e3
    finally:
        for fake in fakes:
            fake.close()
        ef.stop_server()
    pushes = f"{max(loads)} pushes per tab; " if loads else ""
    return dict(case=f"{LOOP_CALLS} f_3Dframe calls, {tabs} tab{'s' if tabs != 1 else ''} open", ours_ms=calls_ms,
                ratio=None if baseline_ms is None else calls_ms / baseline_ms,
                note=f"ratio: to no tab; {pushes}tabs current after {current_ms:,.0f} ms")


def run_figures_bench() -> list[dict[str, Any]]:
    """The plot cases with figures in memory, then the drawing loop with 0, 1 and 3 tabs on a figure server."""
    before = os.environ.get("EGTVIZ_FIGURE")
    try:
        os.environ["EGTVIZ_FIGURE"] = "off"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # the refusals' "not drawn"
            rows = _plot_rows()
        os.environ["EGTVIZ_FIGURE"] = "on"
        baseline = _loop_row(0, None)
        rows.append(baseline)
        rows.extend(_loop_row(tabs, baseline["ours_ms"]) for tabs in (1, 3))
        return rows
    finally:
        if before is None:
            os.environ.pop("EGTVIZ_FIGURE", None)
        else:
            os.environ["EGTVIZ_FIGURE"] = before
