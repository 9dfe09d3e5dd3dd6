"""The figure server's port (an argument, ``use_port`` or ``EGTVIZ_FIGURE_PORT``) and what a drawing prints:
its URL in a script, nothing in a notebook, where the figure itself is the cell's output."""

from __future__ import annotations

import socket

import pytest

import egtviz.egt_figure as ef
from egtviz.egt_figure import _server
from egtviz.egt_figure._server import FIRST_PORT, PORT_ENV, figure_port


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture
def fresh_figures(monkeypatch):
    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    ef.stop_server()
    ef.reset()
    yield
    ef.use_port(None)
    ef.stop_server()
    ef.reset()


def test_the_port_comes_from_the_argument_then_the_variable_then_8080():
    assert figure_port(None, {}) == FIRST_PORT == 8080
    assert figure_port(None, {PORT_ENV: " 9123 "}) == 9123
    assert figure_port(None, {PORT_ENV: "0"}) == 0
    assert figure_port(8765, {PORT_ENV: "9123"}) == 8765


@pytest.mark.parametrize("text", ["80a", "-1", "65536", "8080.0", "1e4"])
def test_a_bad_variable_is_refused_naming_it(text):
    with pytest.raises(ValueError, match=rf"^{PORT_ENV}='{text}': expected a port"):
        figure_port(None, {PORT_ENV: text})


@pytest.mark.parametrize("port", [-1, 65536, 80.0, True, "8080"])
def test_a_bad_port_argument_is_refused(port):
    with pytest.raises(ValueError, match="^port: expected a whole number 0..65535"):
        ef.use_port(port)


def test_a_script_prints_the_url_on_the_chosen_port_and_nothing_of_viser(fresh_figures, capsys):
    port = _free_port()
    ef.use_port(port)
    ef.figure(1)
    out = capsys.readouterr().out
    assert out == f"egtviz figure: http://127.0.0.1:{port}\n"
    assert ef.server_url() == f"http://127.0.0.1:{port}"


def test_the_variable_chooses_the_port(fresh_figures, monkeypatch, capsys):
    port = _free_port()
    monkeypatch.setenv(PORT_ENV, str(port))
    ef.figure(1)
    assert ef.server_url() == f"http://127.0.0.1:{port}"
    assert capsys.readouterr().out == f"egtviz figure: http://127.0.0.1:{port}\n"


def test_choosing_another_port_moves_a_running_server(fresh_figures):
    ef.use_port(0)
    ef.figure(1)
    first = ef.server_url()
    port = _free_port()
    ef.use_port(port)
    assert ef.server_url() is None  # stopped: the next drawing starts it on the new port
    ef.figure(2)
    assert ef.server_url() == f"http://127.0.0.1:{port}" != first


def test_in_a_notebook_a_drawing_prints_nothing_and_shows_the_frame(fresh_figures, monkeypatch, capsys):
    import egtviz.egt_figure as package

    frames: list[str] = []
    monkeypatch.setattr(package, "in_jupyter", lambda: True)
    monkeypatch.setattr(package, "on_cell_end", lambda callback: True)
    monkeypatch.setattr(package, "show_inline", frames.append)
    ef.use_port(0)
    ef.figure(1)
    assert capsys.readouterr().out == ""
    assert frames == [ef.server_url()]
    assert _server.figures_enabled()
