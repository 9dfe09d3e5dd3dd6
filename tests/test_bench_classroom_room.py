"""A small ``egtviz bench classroom --workers 2 --followers M`` run: nothing a tab sent goes unanswered.

Few tabs and a short drag (the benchmark's figures are not asserted: speed is measured, not tested); what is
checked is that every update each dragging tab sent was answered by a panel drawn from it or a later one, and
that every follower on either worker was shown the instructor's last update.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from egtviz.bench.classroom_room import RATE_HZ, run_drag, run_followers

#: Seconds a tab keeps listening after its last panel: the benchmark's 1.5 s is a definition of "answered" on an
#: idle machine; a busy one may take longer to draw the last update, which is late, not lost.
QUIET_S = 8.0

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc")


def test_tabs_dragging_on_two_workers_are_all_answered() -> None:
    run = run_drag(2, 4, seconds=1.5, quiet_s=QUIET_S)
    assert run.sent == 4 * round(1.5 * RATE_HZ)
    assert sum(run.per_worker) == 4
    assert run.applied >= 4  # each tab's drag was drawn, merged or not
    assert run.unanswered == 0
    assert 0 < run.lag_ms[0] <= run.lag_ms[1]
    assert run.rss_mb > 0


def test_followers_on_two_workers_are_shown_the_instructors_last_update() -> None:
    run = run_followers(2, 3, seconds=1.5, quiet_s=QUIET_S)
    assert run.sent == round(1.5 * RATE_HZ)
    assert sum(run.per_worker) == 4  # the instructor and three followers
    assert run.unanswered == 0
    assert 0 < run.lag_ms[0] <= run.lag_ms[1]
