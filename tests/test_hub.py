"""The jupyter-server-proxy entry (``egtviz.jupyter_proxy``) and a notebook figure's address behind the proxy."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pytest

from egtviz.egt_figure._server import jupyter_base_url, notebook_url
from egtviz.jupyter_proxy import ENTRY_NAME, hub_host_names, icon_path, page_at_index, setup_egtviz


@pytest.mark.parametrize(("env", "names"), [
    ({}, ()),
    ({"JUPYTERHUB_PUBLIC_URL": "https://Hub.Example.edu/"}, ("hub.example.edu",)),
    ({"JUPYTERHUB_PUBLIC_URL": "https://hub.example.edu:8443/jupyter/",
      "JUPYTERHUB_PUBLIC_HUB_URL": "https://hub.example.edu:8443/jupyter/hub/"}, ("hub.example.edu",)),
    ({"JUPYTERHUB_HOST": "https://alice.hub.example.edu"}, ("alice.hub.example.edu",)),
    ({"JUPYTERHUB_HOST": "alice.hub.example.edu"}, ("alice.hub.example.edu",)),
    ({"JUPYTERHUB_HOST": "", "JUPYTERHUB_PUBLIC_URL": "not a url at all"}, ()),
])
def test_hub_host_names_come_from_jupyterhubs_environment(env, names):
    assert hub_host_names(env) == names


def test_the_entry_starts_egtviz_on_loopback_on_the_proxys_port_allowing_the_hubs_name():
    entry = setup_egtviz({"JUPYTERHUB_PUBLIC_URL": "https://hub.example.edu/"})
    assert entry["command"][:3] == [sys.executable, "-m", "egtviz.cli"]
    assert entry["command"][3:] == ["serve", "--host", "127.0.0.1", "--port", "{port}",
                                    "--allow-host", "hub.example.edu"]
    assert entry["timeout"] >= 30 and entry["absolute_url"] is False
    assert entry["rewrite_response"] is page_at_index
    assert entry["launcher_entry"]["title"] == "egtviz" == ENTRY_NAME
    icon = Path(entry["launcher_entry"]["icon_path"])
    assert icon == Path(icon_path()) and icon.suffix == ".svg" and b"<svg" in icon.read_bytes()
    assert "--allow-host" not in setup_egtviz({})["command"]


def test_the_entry_is_one_jupyter_server_proxy_accepts():
    pytest.importorskip("jupyter_server_proxy")
    from jupyter_server_proxy.config import get_entrypoint_server_processes

    (process,) = [p for p in get_entrypoint_server_processes() if p.name == ENTRY_NAME]
    assert process.launcher_entry.title == "egtviz"
    assert process.launcher_entry.path_info == "egtviz/"
    assert process.timeout >= 30


def _proxied_page(code: int = 200):
    """A jupyter-server-proxy response to rewrite, as the proxy builds it from egtviz's answer."""
    pytest.importorskip("jupyter_server_proxy")
    from jupyter_server_proxy.handlers import RewritableResponse
    from tornado.httpclient import HTTPRequest, HTTPResponse
    from tornado.httputil import HTTPHeaders

    headers = HTTPHeaders({"Content-Type": "text/html; charset=utf-8", "Content-Encoding": "gzip",
                           "Content-Length": "5"})
    original = HTTPResponse(HTTPRequest("http://localhost:1234/"), code, headers=headers,
                            buffer=io.BytesIO(b"<html"))
    return RewritableResponse(orig_response=original)


def _browser_request(uri: str, method: str = "GET"):
    from tornado.httputil import HTTPHeaders, HTTPServerRequest, RequestStartLine

    return HTTPServerRequest(start_line=RequestStartLine(method, uri, "HTTP/1.1"),
                             headers=HTTPHeaders({"Host": "hub.example.edu"}))


def test_the_routes_root_page_becomes_a_redirect_to_index_html_keeping_the_query():
    response = _proxied_page()
    page_at_index(response=response, request=_browser_request("/user/ann/egtviz/?token=abc&x=1"), path="/")
    assert (response.code, response.reason) == (302, "Found")
    assert response.headers["Location"] == "index.html?token=abc&x=1"
    assert "Content-Encoding" not in response.headers and "Content-Type" not in response.headers
    assert response.body == b""


@pytest.mark.parametrize(("path", "method", "code"), [
    ("/index.html", "GET", 200),  # the page under its own name: served as is
    ("/egtviz-instructor/x", "GET", 200),
    ("/", "POST", 200),
    ("/", "GET", 404),
])
def test_other_answers_pass_unchanged(path, method, code):
    response = _proxied_page(code)
    page_at_index(response=response, request=_browser_request("/egtviz" + path, method), path=path)
    assert response.code == code and response.body == b"<html" and "Location" not in response.headers


def _servers(_env):
    return [{"pid": 111, "port": 8888, "base_url": "/"}, {"pid": 222, "port": 9999, "base_url": "/lab/base/"}]


@pytest.mark.parametrize(("env", "expected"), [
    ({}, "http://127.0.0.1:8081"),  # not under Jupyter: the loopback page
    ({"JPY_PARENT_PID": "333"}, "http://127.0.0.1:8081"),  # a kernel of no server we know (VS Code, say)
    ({"JPY_PARENT_PID": "111"}, "/proxy/8081/"),
    ({"JPY_PARENT_PID": "222"}, "/lab/base/proxy/8081/"),
    ({"JUPYTERHUB_SERVICE_PREFIX": "/user/ann/", "JPY_PARENT_PID": "111"}, "/user/ann/proxy/8081/"),
])
def test_a_notebook_figure_is_framed_through_the_proxy_of_its_server(env, expected):
    pytest.importorskip("jupyter_server_proxy")
    assert notebook_url("http://127.0.0.1:8081", env, _servers) == expected


def test_without_jupyter_server_proxy_the_figure_keeps_its_loopback_address(monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "jupyter_server_proxy" else real(name, *a))
    env = {"JUPYTERHUB_SERVICE_PREFIX": "/user/ann/"}
    assert jupyter_base_url(env, _servers) is None
    assert notebook_url("http://127.0.0.1:8081", env, _servers) == "http://127.0.0.1:8081"


def test_the_entry_imports_neither_the_viewer_nor_numpy():
    """The proxy loads the entry in every user's Jupyter server at its start: it must stay light."""
    from _subprocesses import run

    done = run([sys.executable, "-c", "import sys, egtviz.jupyter_proxy as j; j.setup_egtviz(); "
                "print(sorted(m for m in ('viser', 'numpy', 'egtviz.viewer', 'scipy') if m in sys.modules))"],
               "a Python that imports the proxy's entry to exit", check=True)
    assert done.stdout.strip() == "[]"
