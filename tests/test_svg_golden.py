"""The panels' SVG text is the same to the byte for a fixed set of hand-made inputs (a refactoring check).

Each case draws an image plane or a servo frame from data built here (no scene maths, so no BLAS rounding: the
text depends only on the drawing code) and compares the SHA-256 of the SVG with the one recorded when the drawing
functions were split into named steps. A change meant to alter the drawing changes these hashes: then look at the
new SVGs, and record the hashes this test prints (``pytest -s tests/test_svg_golden.py``) in the same commit.

The cases cover the branches of :func:`egtviz.viewer.render.svg.image_plane_svg` and
:func:`egtviz.viewer.render.servo_svg.servo_image_svg`: epipoles inside, outside and at infinity, epipolar lines in the
image and across a zoomed-out view, conics, a rim and a horizon, a message, a selected and highlighted points,
numbers beside their points, with leader lines, and left out (the crowded note), the numbering note over
``MAX_NUMBERED_POINTS``, and the servo panel's curves, features, legend, caption and message.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from egtviz.scene import Epipole, ImagePlane
from egtviz.viewer.render.panel_view import ViewBox
from egtviz.viewer.render.servo_svg import ServoImage, servo_image_svg
from egtviz.viewer.render.svg import NORMAL, PRESENT, image_plane_svg

W, H = 640, 480


def _pixels(rng: np.random.Generator, n: int, lo: float, hi: float) -> np.ndarray:
    # Rounded to 0.01: the inputs are exact decimals, whatever the platform's last bits.
    return np.round(rng.uniform(lo, hi, size=(n, 2)), 2)


def _plane(n: int, *, cluster: bool, curves: str, message: str | None = None) -> ImagePlane:
    rng = np.random.default_rng(n)
    pts = _pixels(rng, n, 300.0, 360.0) if cluster else _pixels(rng, n, -60.0, 700.0)
    pts[::9] = np.nan  # some points have no image
    visible = np.isfinite(pts[:, 0])
    in_image = visible & (pts[:, 0] >= 0) & (pts[:, 0] <= W) & (pts[:, 1] >= 0) & (pts[:, 1] <= H)
    epipoles = (Epipole("e1", None, np.array([0.6, 0.8]), True, False),
                Epipole("e2'", np.array([900.0, -300.0]), None, False, False),
                Epipole("e3", np.array([330.0, 335.0]), None, False, True))
    extra: dict = {}
    if curves == "lines":
        coefficients = np.column_stack([np.round(rng.normal(size=n), 3), np.ones(n), np.round(rng.uniform(-400, 0, n))])
        extra = dict(lines=np.stack([pts, pts + 40.0], axis=1), line_coefficients=coefficients)
    else:
        t = np.linspace(0.0, np.pi, 25)
        arcs = tuple((np.column_stack([320 + (40 + 3 * i) * np.cos(t), 240 + (30 + 2 * i) * np.sin(t)]),)
                     for i in range(n))
        ring = np.linspace(0.0, 2 * np.pi, 49)
        extra = dict(conics=arcs, rim=np.column_stack([320 + 230 * np.cos(ring), 240 + 230 * np.sin(ring)]),
                     horizon=(np.column_stack([np.linspace(20, 620, 13), np.full(13, 60.0)]),))
    return ImagePlane(camera=f'cam "{n}"', width=W, height=H, points=pts, visible=visible, in_image=in_image,
                      n_hidden=int((~visible).sum()), epipoles=epipoles, message=message, **extra)


def _servo(demo: str) -> ServoImage:
    n = 10
    rng = np.random.default_rng(0)
    goal = np.array([320.0, 240.0]) + np.round(rng.uniform(-60, 60, (n, 2)), 2)
    cur = goal + np.round(rng.uniform(-1.0, 1.0, (n, 2)), 2)
    trails = np.stack([goal + 40.0, goal + 20.0, cur])
    lines = np.stack([cur - 50.0, cur + 50.0], axis=1) if demo == "pinhole" else None
    ring = np.linspace(0.0, 2 * np.pi, 49)
    rim = np.column_stack([320 + 220 * np.cos(ring), 240 + 220 * np.sin(ring)]) if demo == "panoramic" else None
    conics = [(np.column_stack([cur[i, 0] + np.linspace(-30, 30, 7), np.full(7, cur[i, 1])]),) for i in range(n)]
    return ServoImage(demo=demo, width=W, height=H, frame=12, current=cur, desired=goal, trails=trails,
                      lines=lines, conics=conics if demo == "panoramic" else [], rim=rim,
                      epipoles=[("e", np.array([330.0, 250.0])), ("e'", np.array([300.0, 230.0]))],
                      caption="t = 0.60 s  step 1: rotation", message="did not converge (see the status on the left)")


def _cases() -> dict[str, str]:
    spread = _plane(12, cluster=False, curves="lines", message="no epipolar geometry: the centres coincide")
    crowd = _plane(30, cluster=True, curves="conics")
    many = _plane(80, cluster=False, curves="lines")
    out = {}
    for style in (NORMAL, PRESENT):
        s = style.name
        out[f"spread-{s}"] = image_plane_svg(spread, style=style, selected_point=2, highlighted={4}, revision=3)
        out[f"spread-{s}-zoomed-out"] = image_plane_svg(spread, style=style, view=ViewBox(-400.0, -300.0, 1440.0,
                                                                                          1080.0))
        out[f"spread-{s}-zoomed-in"] = image_plane_svg(spread, style=style, view=ViewBox(100.0, 100.0, 200.0, 150.0))
        out[f"crowd-{s}"] = image_plane_svg(crowd, style=style, panel_px=300.0, selected_point=1)
        out[f"crowd-{s}-figure"] = image_plane_svg(crowd, style=style, fixed_size=True, max_height="200px")
        out[f"many-{s}"] = image_plane_svg(many, style=style, selected_point=7, show_labels=True)
        for demo in ("pinhole", "panoramic"):
            out[f"servo-{demo}-{s}"] = servo_image_svg(_servo(demo), style=style, revision=5, panel_px=438.0)
    return out


#: SHA-256 of each case's SVG, recorded from the drawing code before it was split into named steps.
GOLDEN = {
    "crowd-normal": "fadcf26b4e581a2bf16ae404cb3b5faf83d27be3d78cf598a17e480be830d4d9",
    "crowd-normal-figure": "50c5064d42cfa5e93d2fc7bd8b1473958456bde94d832c6390bd5c0dcf0399cc",
    "crowd-present": "6ea42f30ff60a30af33fe361a90b4e79e10b49f25e77c2d67a01a00e6e2b3b8b",
    "crowd-present-figure": "1874d073bfc71264b400bfa0c8a75c3363b0b7bf912689d31ecef4dee1a83a4e",
    "many-normal": "9a289e86f019acbc57aca9b939b81d2a394c74970e242769839939efe95979da",
    "many-present": "7787814154d7fd86a6a060063710f426ec62b9883a96494eb6d1749a5948206e",
    "servo-panoramic-normal": "5676736834430c11c08f7a9ceb06a9c05c35316f462e55687bbad9a8439e4030",
    "servo-panoramic-present": "c3604d94ff5ef5eb33f5fe87d354b3da56a6651c53e5681e7c22d7053573aef7",
    "servo-pinhole-normal": "acdd7b238016e16cd576778cfb71b3d68dc6fd247c673190707ba91f3159fffc",
    "servo-pinhole-present": "76cc8167f1eae9316d44f2e9fb39117c8cdb088519074ee01bf341ca7aa7761c",
    "spread-normal": "263a2a4b949cfab9ea8486038b7b3a63a9d6d2ac2bb92713c9e504526fafd050",
    "spread-normal-zoomed-in": "025a659c968b50d4ea9b483b15013a44b6181ea31b49f1d22f90fa917252d3c9",
    "spread-normal-zoomed-out": "7ee79ab25ad3495096fb226e22aec437ed9e38c42b3f1bb2a6d71c797af0dce9",
    "spread-present": "36ae0eba90dcd47a95b6358ca301ded88aa92ec18f6f18b81c39db5d85de29ef",
    "spread-present-zoomed-in": "e2ab362778ef140ac79c8e7071d1d123b332685442a42acb0f653dc1d26c0c72",
    "spread-present-zoomed-out": "7ddb34cfd8ca08f8efa445e23c6ad6dc94c393042a6e80e47da368186aca37f9",
}


@pytest.fixture(scope="module")
def cases() -> dict[str, str]:
    return _cases()


def test_the_cases_cover_every_branch(cases):
    svg = "".join(cases.values())
    for kind in ("epipole-arrow", "epipolar-line", "epipolar-conic", "rim", "horizon", "message", "label-leader",
                 "crowded-note", "numbering-note", "hidden-count", "trail", "desired", "legend", "caption"):
        assert f'data-kind="{kind}"' in svg, kind
    for where in ("inside", "outside", "infinity"):
        assert f'data-where="{where}"' in svg, where


def test_the_svg_text_is_unchanged(cases):
    got = {name: hashlib.sha256(svg.encode()).hexdigest() for name, svg in cases.items()}
    changed = sorted(name for name in got if got[name] != GOLDEN.get(name))
    if changed:
        print("GOLDEN = {\n" + "".join(f'    "{k}": "{got[k]}",\n' for k in sorted(got)) + "}")
    assert changed == []
