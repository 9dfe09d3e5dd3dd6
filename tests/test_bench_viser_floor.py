"""The floor measurement of ``egtviz bench classroom``: every pose the tab sends reaches the callback, once."""

import math

import pytest

from egtviz.bench.viser_floor import FloorRun, format_floor, viser_floor


def test_floor_counts_every_update_it_sent():
    run = viser_floor(rate=100.0, seconds=0.5)
    assert run.sent == 50
    assert run.callbacks == 50  # the figure is per update received, and none was dropped or doubled
    assert run.cpu_s > 0.0
    assert math.isclose(run.cpu_ms_per_update, 1e3 * run.cpu_s / 50)
    assert "50 of 50 received" in format_floor([run])


def test_floor_refuses_rates_and_durations_that_are_not_positive():
    with pytest.raises(ValueError, match="rate, seconds"):
        viser_floor(rate=0.0)
    with pytest.raises(ValueError, match="rate, seconds"):
        viser_floor(seconds=-1.0)


def test_floor_with_no_callback_has_no_figure():
    assert math.isnan(FloorRun(20.0, 10, 0, 0.01).cpu_ms_per_update)
