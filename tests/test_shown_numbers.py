"""One number rule for every label, read-out, plot tick, field and export: rounding (below 1e-12 of the vector's
largest component) shows as 0, and a zero never carries a minus sign."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from egtviz.scene import Epipole, ImagePlane
from egtviz.scene.annotations import Plot
from egtviz.scene.shown_numbers import format_value, format_vector, shown_components
from egtviz.viewer.workbench.app import pair_html
from egtviz.controllers.workbench_fields import format_numbers
from egtviz.viewer.render.panel_view import ViewBox
from egtviz.viewer.render.plot_svg import plot_svg
from egtviz.viewer.render.svg import image_plane_svg

NOISE = (-1.5e-16, -0.0)


def texts(svg: str, kind: str) -> list[str]:
    root = ET.fromstring(svg)
    return ["".join(el.itertext()) for el in root.iter() if el.get("data-kind") == kind]


def plane(epipoles=()) -> ImagePlane:
    return ImagePlane(camera="c", width=640, height=480, points=np.array([[100.0, 100.0]]), visible=np.array([True]),
                      in_image=np.array([True]), n_hidden=0, epipoles=tuple(epipoles))


@pytest.mark.parametrize("noise", NOISE)
def test_the_rule(noise):
    assert format_vector((5.667, noise)) == "5.667, 0"
    assert format_vector((5.667, noise), ".1f") == "5.7, 0.0"
    assert shown_components((noise, 3.0)) == (0.0, 3.0)
    assert format_value(-0.0) == "0" and format_value(noise, ".2f") == "0.00"
    assert format_value(-0.04, ".1f") == "0.0"
    # A lone small number is not rounding; at 1e-12 of the largest and above it is a value.
    assert format_vector((1e-13, 0.0)) == "1e-13, 0"
    assert format_vector((1.0, 2e-12)) == "1, 2e-12"


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e9, max_value=1e9), min_size=1,
                max_size=4), st.sampled_from([".4g", ".1f", ".2f", ".3g", " .4e", ".0f"]))
def test_no_formatted_zero_carries_a_sign(values, spec):
    for text in format_vector(values, spec).split(", "):
        assert not re.fullmatch(r"\s*-0(\.0*)?(e[+-]\d+)?", text), text


@pytest.mark.parametrize("noise", NOISE)
def test_panel_epipole_labels(noise):
    outside = Epipole("e1", np.array([700.0, noise]), None, False, False)
    assert "e1 (700, 0)" in texts(image_plane_svg(plane([outside])), "epipole-label")
    shown = Epipole("e2", np.array([5.667, noise]), None, False, False)
    svg = image_plane_svg(plane([shown]), view=ViewBox(-20.0, -20.0, 660.0, 500.0))
    assert "e2 (5.667, 0)" in texts(svg, "epipole-label")
    far = Epipole("e1", None, np.array([1.0, noise]), True, False)
    assert any("direction (1.00, 0.00)" in t for t in texts(image_plane_svg(plane([far])), "epipole"))


@pytest.mark.parametrize("noise", NOISE)
def test_plot_ticks_and_exported_plot_labels(noise):
    plot = Plot(number=1, points=((5.667, noise), (1.0, 1.0)), epipoles=((5.667, noise, 1.0),))
    svg = plot_svg(plot)
    labels = texts(svg, "epipole-label")
    assert labels and all("e-" not in t and "-0" not in t for t in labels), labels
    root = ET.fromstring(svg)
    ticks = [t.text for el in root.iter() if el.get("data-kind") == "axes" for t in el.iter() if t.text]
    assert ticks and not [t for t in ticks if re.fullmatch(r"-0(\.0*)?", t)], ticks


@pytest.mark.parametrize("noise", NOISE)
def test_the_readout(noise):
    F = np.array([[0.0, noise, 0.1], [-0.2, 0.0, 0.3], [noise, 0.4, 0.5]])
    pair = SimpleNamespace(names=("a", "b"), message="", F=F, E=F, rank=2,
                           e1=np.array([5.667, noise, 1.0]), e2=np.array([noise, 2.0, 0.0]))
    html = pair_html(SimpleNamespace(pair=pair))
    assert "e1 = (5.7, 0.0) px" in html
    assert "e2 = (0, 2, 0) (at infinity)" in html
    assert not re.search(r"-0(\.0+)?(e[+-]00)?\b", html), html


@pytest.mark.parametrize("noise", NOISE)
def test_a_vector_field(noise):
    assert format_numbers((20.5, noise, 3.0)) == "20.5, 0, 3"
