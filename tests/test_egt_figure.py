"""EGT's figures: the front-end's figure state after each example script, hold / figure / clf semantics,
drawings that cannot be drawn, reflected cameras, the planar-mirror scene, annotations as scene data,
their 3D nodes and plot panels, and the server and notebook checks.

Expected values come from the example scripts' own inputs (the EGT paper's Examples 1-4 and EGT 2.0's
demos) and from the facade's computed values, which are golden-tested elsewhere; the geometric identities
(lines through the epipole, mirror reflections, the mirror's F) are checked directly.
"""

from __future__ import annotations

import re
import runpy
import types
from pathlib import Path

import numpy as np
import pytest

import egtviz.egt_figure as ef
from egtviz.egt import (
    clf,
    eye,
    f_3Dcamera,
    f_3Dframe,
    f_3Dplane,
    f_3Dreflenum,
    f_3Dsurface,
    f_3Dwf,
    f_epipline,
    f_epipole,
    f_panparconic,
    f_perspproj,
    f_reflcamera,
    f_reflpersproj,
    f_Rt2H,
    f_scenepnt,
    figure,
    hold_on,
    pi,
    rotoy,
    rotoz,
)
from egtviz.egt_figure._server import figures_enabled, in_jupyter, show_inline
from egtviz.scene import SCENES, SceneFileError, SceneModel, compute_derived, scene_from_bytes, scene_to_bytes
from egtviz.scene.annotations import Annotations, Frame, PlanarMirror, Plot, PlotCircle, annotations_from_dict
from egtviz.scene.specs import SceneError

from _waiting import PATIENCE

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(autouse=True)
def headless_figures(monkeypatch):
    """Figures in memory only, and a fresh registry for every test."""
    monkeypatch.setenv("EGTVIZ_FIGURE", "off")
    ef.reset()
    yield
    ef.reset()


def _run(script: str):
    runpy.run_path(str(EXAMPLES / script), run_name="__main__")
    fig = ef.current_figure()
    scene = fig.scene()
    compute_derived(scene)  # the viewer can draw it
    # The figure is scene data: it survives the file format unchanged.
    assert scene_from_bytes(scene_to_bytes(scene), "figure").annotations == scene.annotations
    return fig, scene


def _counts(scene) -> dict:
    a = scene.annotations
    return {
        "cameras": [(c.name, c.kind) for c in scene.cameras],
        "points": len(scene.points),
        **{k: len(getattr(a, k)) for k in ("frames", "polylines", "point_sets", "meshes", "mirrors", "plots")},
        "messages": a.messages,
    }


# -- the example scripts ---------------------------------------------------------------------------------


def test_example_1_figure(capsys):
    fig, scene = _run("01_pinhole_placement.py")
    assert _counts(scene) == {"cameras": [("cam1", "pinhole")], "points": 4, "frames": 2, "polylines": 0,
                              "point_sets": 0, "meshes": 0, "mirrors": 0, "plots": 1, "messages": ()}
    cam = scene.cameras[0]
    # K = I: the camera carries it (focal 1 m, 1 pixel per metre, principal point at the origin).
    np.testing.assert_allclose(cam.camera().K, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(cam.camera().pose.matrix, f_Rt2H(rotoy(pi / 4), [-10, -5, 0]), atol=1e-9)
    (plot,) = scene.annotations.plots
    # The paper's Example 1 pixels (printed by the script; derived by hand in test_egt_tutorial).
    np.testing.assert_allclose(plot.points, [[-1 / 15, 0.282843], [5 / 21, 0.202031], [5 / 21, -0.202031],
                                             [-1 / 15, -0.282843]], atol=1e-6)
    assert plot.title == "Figure 1" and plot.image_size is None and not plot.lines
    labels = sorted(f.label for f in scene.annotations.frames)
    assert labels == ["_cam", "_wf"]


def test_example_2_figure():
    fig, scene = _run("02_panoramic_placement.py")
    c = _counts(scene)
    assert c["cameras"] == [("pano1", "panoramic")] and c["points"] == 1 and c["polylines"] == 1
    cam = scene.cameras[0]
    assert (cam.mirror, cam.a, cam.b) == ("hyperbolic", 3.0, 1.0)
    np.testing.assert_allclose(cam.position, [-5, -5, 0])
    np.testing.assert_allclose(cam.ypr_deg, [45, 0, 0], atol=1e-9)
    # The mirror point: the script's Xh (mirror frame) turned by rotoz(pi/4) and moved to the focus.
    Xh = np.array([0.603179, 0.0, 0.341209])
    (ps,) = scene.annotations.point_sets
    np.testing.assert_allclose(ps.points[0], rotoz(pi / 4) @ Xh + [-5, -5, 0], atol=1e-6)
    ray = scene.annotations.polylines[0]
    assert ray.kind == "ray" and ray.points[0] == (0.0, 0.0, 4.0)


def test_example_3_figure_two_images_with_epipoles_and_lines():
    fig, scene = _run("03_pinhole_epipolar.py")
    c = _counts(scene)
    assert c["cameras"] == [("cam1", "pinhole"), ("cam2", "pinhole")] and c["points"] == 2 and c["plots"] == 2
    p1, p2 = scene.annotations.plots
    assert (p1.number, p2.number) == (1, 2)
    H1 = f_Rt2H(rotoz(pi / 4), [-10, -10, 0])
    H2 = f_Rt2H(eye(3), [0, 0, 0])
    P = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    np.testing.assert_allclose(np.array(p1.points).T, f_perspproj(P, H1, eye(3)), atol=1e-12)
    np.testing.assert_allclose(np.array(p2.points).T, f_perspproj(P, H2, eye(3)), atol=1e-12)
    # Epipoles by hand (test_egt_tutorial): e1 = (sqrt(1/2), -sqrt(1/2), 1), e2 = (1, 0, 1).
    np.testing.assert_allclose(p1.epipoles, [[np.sqrt(0.5), -np.sqrt(0.5), 1.0]], atol=1e-9)
    np.testing.assert_allclose(p2.epipoles, [[1.0, 0.0, 1.0]], atol=1e-9)
    for plot in (p1, p2):
        assert len(plot.lines) == 2
        L, e = np.array(plot.lines), np.array(plot.epipoles[0])
        np.testing.assert_allclose(L @ e, 0.0, atol=1e-9)  # every line through its image's epipole
        Lp = np.column_stack([plot.line_points, np.ones(2)])
        np.testing.assert_allclose(np.sum(L * Lp, axis=1), 0.0, atol=1e-9)  # and through its point


def test_example_4_figure():
    fig, scene = _run("04_panoramic_epipolar.py")
    c = _counts(scene)
    assert c["cameras"] == [("pano1", "panoramic"), ("pano2", "panoramic")] and c["points"] == 8
    # f_panproj with a colour: one point set (mirror points) and one ray per seen point, per camera.
    seen = [len(ps.points) for ps in scene.annotations.point_sets]
    assert len(seen) == 2 and c["polylines"] == sum(seen) and all(0 < k <= 8 for k in seen)
    d = compute_derived(scene)
    assert all(len(d.image_planes[n].epipoles) == 2 for n in ("pano1", "pano2"))


def test_example_5_figure_uses_the_figure_numbers_of_f_epipline():
    fig, scene = _run("05_pinhole_demo.py")
    assert [p.number for p in scene.annotations.plots] == [2, 3]
    assert [c.name for c in scene.cameras] == ["desired", "actual"]
    assert all(len(p.lines) == 2 and len(p.epipoles) == 1 for p in scene.annotations.plots)


def test_example_6_figure_parabolic_mirrors():
    fig, scene = _run("06_panoramic_demo.py")
    assert [(c.mirror, c.a) for c in scene.cameras] == [("parabolic", 0.03), ("parabolic", 0.03)]
    assert len(scene.points) == 8


def test_example_7_figure_planar_mirrors_and_virtual_cameras():
    fig, scene = _run("07_planar_mirror_demo.py")
    c = _counts(scene)
    assert c["cameras"] == [("camera", "pinhole"), ("v1", "pinhole"), ("v2", "pinhole")]
    assert c["mirrors"] == 2 and c["plots"] == 2 and c["messages"] == ()
    mirrored = [f for f in scene.annotations.frames if f.mirrored]
    assert len(mirrored) == 2 and all("mirrored" in f.label for f in mirrored)
    # Mirror 1 is the plane y = 0 (n = (0, -1, 0)) drawn over x in [0, 3], z in [-1.5, 1.5].
    m1 = scene.annotations.mirrors[0]
    np.testing.assert_allclose(m1.normal, [0, -1, 0])
    np.testing.assert_allclose(m1.centre, [1.5, 0.0, 0.0])
    # The plots hold the reflected images: f_reflpersproj's pixels, K's image 1280 x 960.
    from egtviz.egt import f_3Drandpoint

    P = f_3Drandpoint(20, [0.5, -1.0, 0.0], 0.5, rng=0)
    K = np.array([[700, 0, 640], [0, 700, 480], [0, 0, 1]], float)
    H = f_Rt2H(rotoy(-23 * pi / 180), [0.6, -2.8, -1.0])
    U1, _ = f_reflpersproj([0, -1, 0], 0, H, K, P)
    p1 = scene.annotations.plots[0]
    assert p1.image_size == (1280, 960)
    np.testing.assert_allclose(np.array(p1.points).T, U1, atol=1e-9)


# -- hold, figure(n), clf -----------------------------------------------------------------------------


def test_hold_on_adds_and_the_same_points_are_drawn_once():
    hold_on()
    f_scenepnt(np.array([[0, 1], [2, 3], [4, 5]], float))
    f_scenepnt(np.array([[0, 1], [2, 3], [4, 5]], float))
    f_scenepnt(np.array([7, 8, 9], float))
    assert ef.current_figure().scene().points == ((0.0, 2.0, 4.0), (1.0, 3.0, 5.0), (7.0, 8.0, 9.0))


def test_figure_selects_and_creates_figures_and_clf_clears_only_the_current_one():
    f_3Dwf("k", 1)
    assert figure(3) == 3
    f_scenepnt([1.0, 2.0, 3.0])
    assert figure() == 4  # a new figure after the highest number, like MATLAB's figure
    assert sorted(ef.figures()) == [1, 3, 4]
    figure(3)
    assert ef.current_figure().scene().points == ((1.0, 2.0, 3.0),)
    assert ef.current_figure().scene().title == "Figure 3"
    clf()
    assert ef.current_figure().scene().points == () and ef.current_figure().annotations().empty
    figure(1)
    assert len(ef.current_figure().annotations().frames) == 1
    with pytest.raises(ValueError, match="number"):
        figure(0)


def test_unknown_kind_and_bad_data_are_messages_not_errors():
    f_3Dwf()
    before = ef.current_figure().scene()
    with pytest.warns(RuntimeWarning, match="unknown drawing 'hologram'"):
        assert ef.draw("hologram", points=np.zeros((3, 2))) is False
    with pytest.warns(RuntimeWarning, match="line3d: not drawn"):
        assert ef.draw("line3d", points=np.zeros((2, 2))) is False
    scene = ef.current_figure().scene()
    assert scene.cameras == before.cameras and scene.annotations.frames == before.annotations.frames
    msgs = scene.annotations.messages
    assert len(msgs) == 2 and "hologram" in msgs[0] and "image_points" in msgs[0]  # lists the known kinds


def test_a_ninth_camera_is_refused_in_the_figure_and_the_others_stay():
    for k in range(8):
        f_3Dcamera(f_Rt2H(eye(3), [float(k), 0.0, 0.0]))
    with pytest.warns(RuntimeWarning, match="camera: not drawn"):
        f_3Dcamera(f_Rt2H(eye(3), [9.0, 0.0, 0.0]))
    scene = ef.current_figure().scene()
    assert len(scene.cameras) == 8 and "at most 8" in scene.annotations.messages[-1]


def test_a_camera_drawn_twice_is_one_camera_and_its_plot_gives_it_K():
    H = f_Rt2H(eye(3), [0, -5, 0])
    K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
    f_3Dcamera(H, "r", 1)
    f_3Dcamera(H, "g", 1, 2)
    X = np.array([[0.5, 0.0, 0.2]]).T
    f_scenepnt(X)
    f_perspproj(X, H, K, 1)
    scene = ef.current_figure().scene()
    (cam,) = scene.cameras
    np.testing.assert_allclose(cam.camera().K, K)
    assert (cam.width, cam.height) == (640, 640 * 3 // 4)
    # The camera's panel and the plot show the same pixel: (0.5 / 5 * 500 + 320, -0.2 / 5 * 500 + 240).
    plane = compute_derived(scene).image_planes[cam.name]
    np.testing.assert_allclose(plane.points[0], [370.0, 220.0], atol=1e-9)
    np.testing.assert_allclose(scene.annotations.plots[0].points[0], [370.0, 220.0], atol=1e-9)


# -- reflected (left-handed) cameras ------------------------------------------------------------------


def test_a_reflected_camera_is_its_proper_camera_and_a_mirrored_frame():
    n, d = np.array([0.0, 1.0, 0.0]), 2.0
    H = f_Rt2H(rotoy(0.3), [0.5, -3.0, 0.4])
    K = np.array([[600.0, 0.0, 320.0], [0.0, 600.0, 240.0], [0.0, 0.0, 1.0]])
    Hv = f_reflcamera(n, d, H)
    assert np.linalg.det(Hv[:3, :3]) == pytest.approx(-1.0)
    f_perspproj(np.array([[0.0, 0.0, 0.0]]).T, Hv, K, 1)  # gives the camera its K
    f_3Dcamera(Hv, "g", 1, 1, "virtual")
    scene = ef.current_figure().scene()
    (cam,) = scene.cameras
    # Proper camera: the reflected axes with x reversed, at the reflected centre (y' = 2 d - y = 7).
    np.testing.assert_allclose(cam.camera().pose.R, Hv[:3, :3] @ np.diag([-1.0, 1.0, 1.0]), atol=1e-9)
    np.testing.assert_allclose(cam.position, [0.5, 7.0, 0.4], atol=1e-12)
    (frame,) = scene.annotations.frames
    assert frame.mirrored and frame.label.endswith("(mirrored)")
    np.testing.assert_allclose(np.array(frame.axes).T, Hv[:3, :3], atol=1e-12)
    # Its panel is the reflected image flipped left-right about u0: u_panel = 2 u0 - u_reflected.
    X = np.array([[0.3, 0.0, 0.5], [-0.4, 1.0, 0.1]]).T
    Uv = f_perspproj(X, Hv, K)
    px = cam.camera().project(X.T).pixels
    np.testing.assert_allclose(px[:, 0], 640.0 - Uv[0], atol=1e-9)
    np.testing.assert_allclose(px[:, 1], Uv[1], atol=1e-9)


# -- the planar-mirror built-in scene ---------------------------------------------------------------------


def _mirror_F(scene):
    """The planar mirror's F between the real image and the proper virtual camera's image, by hand:
    m_reflected^T [e]x m = 0 with e = K R^T n, and m_virtual = M m_reflected, M = K S K^-1 (an involution),
    so F = M^T [e]x."""
    real = scene.camera("cam").camera()
    n = np.array(scene.annotations.mirrors[0].normal)
    e = real.K @ real.pose.R.T @ n
    E = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    M = real.K @ np.diag([-1.0, 1.0, 1.0]) @ np.linalg.inv(real.K)
    F = M.T @ E
    return F / np.linalg.norm(F), e


def _same_up_to_sign(A, B, atol=1e-9):
    return min(np.abs(A - B).max(), np.abs(A + B).max()) < atol


def test_mirror_scene_virtual_camera_is_the_reflection_and_follows_a_drag():
    scene = SCENES["mirror"]()
    assert scene.camera_names == ("cam", "cam_virtual") and "cam_virtual" in scene.locked
    real, virtual = scene.camera("cam"), scene.camera("cam_virtual")
    # The mirror is y = 3: the virtual centre is (x, 6 - y, z).
    np.testing.assert_allclose(virtual.position, [-3.0, 14.0, 1.5], atol=1e-9)
    d = compute_derived(scene)
    F, e = _mirror_F(scene)
    assert _same_up_to_sign(d.pair.F, F)
    # e1 (image of the virtual centre in the real image) is the vanishing point of the normal.
    np.testing.assert_allclose(d.pair.e1[:2] / d.pair.e1[2], e[:2] / e[2], atol=1e-6)
    model = SceneModel(scene)
    R = real.camera().pose.R @ np.array([[np.cos(0.2), -np.sin(0.2), 0], [np.sin(0.2), np.cos(0.2), 0], [0, 0, 1]])
    model.set_camera_pose("cam", (-1.0, -7.0, 2.0), R)
    moved = model.scene
    np.testing.assert_allclose(moved.camera("cam_virtual").position, [-1.0, 13.0, 2.0], atol=1e-9)
    np.testing.assert_allclose(moved.camera("cam_virtual").camera().pose.R,
                               np.diag([1.0, -1.0, 1.0]) @ R @ np.diag([-1.0, 1.0, 1.0]), atol=1e-9)
    assert _same_up_to_sign(model.derived.pair.F, _mirror_F(moved)[0])
    # The locked virtual camera cannot be moved away from the reflection.
    model.set_camera_pose("cam_virtual", (0.0, 20.0, 0.0), model.scene.camera("cam_virtual").camera().pose.R)
    np.testing.assert_allclose(model.scene.camera("cam_virtual").position, [-1.0, 13.0, 2.0], atol=1e-9)


def test_mirror_scene_survives_its_file_format():
    scene = SCENES["mirror"]()
    again = scene_from_bytes(scene_to_bytes(scene), "mirror.json")
    assert again.annotations == scene.annotations and again.cameras == scene.cameras


# -- annotations as scene data -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "data, match",
    [
        ({"frames": [{"colour": "red"}]}, r"annotations.frames\[0\]: frame colour"),
        ({"frames": [{"axes": [[1, 0, 0], [1, 0, 0], [0, 0, 1]]}]}, "orthonormal"),
        ({"meshes": [{"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 3]]}]}, "vertex indices below 3"),
        ({"plots": [{"number": 1}, {"number": 1}]}, "numbers must be unique"),
        ({"plots": [{"lines": [[1, 0, 0]], "line_points": []}]}, "one per line"),
        ({"mirrors": [{"normal": [0, 0, 0]}]}, "non-zero"),
        ({"mirrors": [{"reflects": "cam"}]}, "both camera names"),
        ({"polylines": [{"points": [[0, 0, 0]]}]}, "2 to"),
        ({"spirals": []}, "unknown entry"),
        ({"labels": [{"text": "a", "size": 3}]}, "unknown field"),
    ],
)
def test_bad_annotations_are_refused_naming_the_entry(data, match):
    with pytest.raises(SceneError, match=match):
        annotations_from_dict(data)


def test_a_scene_file_with_bad_annotations_names_the_file_and_entry():
    text = b'{"annotations": {"point_sets": [{"points": [[0, 0, 1e9]]}]}}'
    with pytest.raises(SceneFileError, match=r"bad\.json: .*point_sets\[0\]"):
        scene_from_bytes(text, "bad.json")


def test_a_mirror_that_reflects_a_panoramic_camera_is_refused():
    from egtviz.scene import PanoramicSpec, Scene

    with pytest.raises(SceneError, match="not a pin-hole camera"):
        Scene(cameras=(PanoramicSpec("pano"),),
              annotations=Annotations(mirrors=(PlanarMirror(reflects="pano", virtual="v"),)))


def test_frame_handedness():
    assert not Frame().mirrored
    assert Frame(axes=((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))).mirrored


# -- other EGT drawing functions -------------------------------------------------------------------------


def test_surface_plane_reflenum_and_circle_drawings():
    f_3Dsurface("sphere", None, None, 2.0, 6, 1)
    f_3Dplane([0, 0, 2], 1.0, [-1, 1], [-2, 2], [0, 4])  # the plane z = 1 (unit normal)
    f_3Dreflenum([{"point": [0, 0, 1], "number": 7}, {"point": [1, 0, 1], "number": 9}])
    f_panparconic(np.array([[1.0, 0.0, -1.0], [0.0, 1.0, -1.0]]).T, np.eye(4), None, 0.5, 1.0, 2, "b")
    a = ef.current_figure().scene().annotations
    (mesh,) = a.meshes
    assert len(mesh.vertices) == 36 and len(mesh.faces) == 2 * 5 * 5
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 2.0, atol=1e-9)  # a sphere of radius 2
    (plane,) = a.mirrors
    np.testing.assert_allclose(plane.normal, [0, 0, 1])
    np.testing.assert_allclose(plane.centre, [0, 0, 1.0])  # the box centre (0, 0, 2) moved onto z = 1
    (ps,) = a.point_sets
    assert ps.labels == ("7", "9")
    (plot,) = a.plots
    assert len(plot.circles) == 1 and plot.circles[0].colour == "#0000e0"
    assert [p.kind for p in a.polylines] == ["normal"]


def test_f_3Dframe_labels_and_length():
    H = f_Rt2H(eye(3), [1, 2, 3])
    f_3Dframe(H, "b", 2.5, "_{cam}")
    (frame,) = ef.current_figure().annotations().frames
    assert frame.label == "_cam" and frame.length == 2.5 and frame.colour == "#0000e0"
    np.testing.assert_allclose(frame.origin, [1, 2, 3])
    np.testing.assert_allclose(np.array(frame.axes).T, H[:3, :3], atol=1e-12)


# -- 2D plot panels and 3D nodes -----------------------------------------------------------------------------


def _kinds(svg: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for k in re.findall(r'data-kind="([a-z-]+)"', svg):
        out[k] = out.get(k, 0) + 1
    return out


def test_example_3_plot_panels_count_their_marks():
    from egtviz.viewer.render.plot_svg import plot_svg

    _, scene = _run("03_pinhole_epipolar.py")
    for plot in scene.annotations.plots:
        svg = plot_svg(plot)
        k = _kinds(svg)
        assert (k.get("point"), k.get("epipolar-line"), k.get("epipole")) == (2, 2, 1), k
        assert "border" not in k  # K = I: no image rectangle
        assert f'data-plot="{plot.number}"' in svg and f'data-camera="Figure {plot.number}"' in svg
        assert f'data-label="e{plot.number}"' in svg


def test_plot_panel_circles_and_image_border():
    from egtviz.viewer.render.plot_svg import plot_svg, plot_view

    plot = Plot(number=4, points=((100.0, 50.0),), circles=(PlotCircle((320.0, 240.0), 100.0, "#0000e0"),),
                image_size=(640, 480))
    svg = plot_svg(plot)
    k = _kinds(svg)
    assert k["circle"] == 1 and k["border"] == 1 and k["point"] == 1
    view = plot_view(plot)
    # The view holds the image rectangle plus 6 % of its span on each side, at 4:3.
    assert view.u0 == pytest.approx(-0.06 * 640) and view.width == pytest.approx(1.12 * 640)
    assert view.width / view.height == pytest.approx(4 / 3)


def test_annotations_3d_nodes():
    import viser

    from egtviz.viewer.workbench.annotations3d import Annotations3D

    _, scene = _run("07_planar_mirror_demo.py")
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        nodes = Annotations3D(server.scene)
        nodes.draw(scene.annotations)
        a = scene.annotations
        assert nodes.counts["frames"] == len(a.frames) == 4
        assert nodes.counts["frame_labels"] == 3 * len(a.frames)
        assert nodes.counts["mirrors"] == 2
        first = list(nodes._nodes)
        nodes.draw(scene.annotations)  # unchanged: nothing rebuilt
        assert nodes._nodes == first
        nodes.draw(Annotations())
        assert nodes.counts == {} and nodes._nodes == []
    finally:
        server.stop()


# -- server, environment and notebook checks ---------------------------------------------------------------


def test_figures_enabled_reads_the_environment():
    assert figures_enabled({}) is True
    assert figures_enabled({"EGTVIZ_FIGURE": "off"}) is False
    assert figures_enabled({"EGTVIZ_FIGURE": "0"}) is False
    assert figures_enabled({"EGTVIZ_FIGURE": "on"}) is True
    assert figures_enabled({"EGTVIZ_FIGURE": " No "}) is False


def test_jupyter_detection_without_jupyter():
    assert in_jupyter({}) is False
    assert in_jupyter({"IPython": types.SimpleNamespace(get_ipython=lambda: None)}) is False
    terminal = types.SimpleNamespace()  # a terminal IPython shell has no kernel
    assert in_jupyter({"IPython": types.SimpleNamespace(get_ipython=lambda: terminal)}) is False
    kernel_shell = types.SimpleNamespace(kernel=object())
    assert in_jupyter({"IPython": types.SimpleNamespace(get_ipython=lambda: kernel_shell)}) is True

    def broken():
        raise RuntimeError("no shell")

    assert in_jupyter({"IPython": types.SimpleNamespace(get_ipython=broken)}) is False
    shown = []
    display = types.SimpleNamespace(IFrame=lambda url, width, height: ("iframe", url, width, height),
                                    display=shown.append)
    frame = show_inline("http://127.0.0.1:8080", {"IPython": types.SimpleNamespace(display=display)})
    assert shown == [frame] == [("iframe", "http://127.0.0.1:8080", "100%", 640)]


def test_the_server_starts_once_prints_its_url_once_and_tabs_show_the_current_figure(monkeypatch, capsys):
    from egtviz.viewer.server.headless import FakeTab

    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setenv("EGTVIZ_FIGURE_PORT", "0")  # any free port: another test process may be serving figures
    try:
        f_3Dwf("k", 1)
        url = ef.server_url()
        assert url is not None and re.fullmatch(r"http://127\.0\.0\.1:\d+", url)
        f_3Dcamera(f_Rt2H(eye(3), [0, -5, 0]))
        out = capsys.readouterr().out
        assert out.count("egtviz figure: http://127.0.0.1:") == 1
        server = ef.figure_server()
        tab = FakeTab(server.server.get_port())
        (view,) = server.app.wait_for_view(timeout=PATIENCE)
        assert ef.flush(PATIENCE)
        assert view.model.scene.title == "Figure 1" and len(view.model.scene.cameras) == 1
        f_scenepnt(np.array([[0.0, 0.0, 1.0]]).T)
        assert ef.flush(PATIENCE)
        assert len(view.model.scene.points) == 1  # pushed to the open tab
        f_perspproj(np.array([[0.0, 0.0, 1.0]]).T, f_Rt2H(eye(3), [0, -5, 0]), eye(3), 1)
        assert ef.flush(PATIENCE)
        plots = [svg for svg in view.svgs.values() if 'data-plot="1"' in svg]
        assert len(plots) == 1 and _kinds(plots[0])["point"] == 1  # the plot has its panel in the tab
        with pytest.warns(RuntimeWarning):
            ef.draw("hologram")
        assert ef.flush(PATIENCE)
        assert view.controls.title.content.count('data-egtviz="figure-message"') == 1  # the reason, under the title
        figure(2)
        assert ef.flush(PATIENCE)
        assert view.model.scene.title == "Figure 2" and not view.model.scene.cameras
        tab.close()
    finally:
        ef.stop_server()
    assert ef.server_url() is None


def test_epipolar_lines_without_figure_numbers_find_the_plot_of_their_points():
    H1 = f_Rt2H(rotoz(pi / 4), [-10, -10, 0])
    H2 = f_Rt2H(eye(3), [0, 0, 0])
    P = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    U1 = f_perspproj(P, H1, eye(3), 1)
    U2 = f_perspproj(P, H2, eye(3), 1)
    _, _, F = f_epipole(H1, H2, eye(3), eye(3))
    # A plot flag but no figure numbers: each image's lines go to the plot holding its points.
    f_epipline(U1, U2, F, 1)
    plots = ef.current_figure().scene().annotations.plots
    assert [(p.number, len(p.points), len(p.lines)) for p in plots] == [(1, 2, 2), (2, 2, 2)]


def test_show_returns_at_once_without_a_server(monkeypatch):
    monkeypatch.setattr("sys.argv", ["script.py"])
    f_3Dwf()
    assert ef.server_url() is None
    ef.show()  # figures are off: nothing is served, nothing to wait for
    ef.show(wait=True)


def test_a_K_the_scene_cannot_hold_is_a_message_and_the_camera_keeps_default_intrinsics():
    H = f_Rt2H(eye(3), [0, -5, 0])
    f_3Dcamera(H)
    K = np.diag([0.5, 0.5, 1.0])  # half a pixel of focal length: below the scene's 1 px
    with pytest.warns(RuntimeWarning, match="K not used"):
        f_perspproj(np.array([[0.0, 0.0, 0.0]]).T, H, K, 1)
    scene = ef.current_figure().scene()
    assert scene.cameras[0].focal_length == 0.008  # the workbench's default camera
    assert len(scene.annotations.plots) == 1 and "K not used" in scene.annotations.messages[0]
