"""A course served to a class on a real viser server, for the headless tests of the class on the course's pages."""

from __future__ import annotations

import time

import pytest
import viser

from egtviz.classroom import Mode
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom import host as host_module
from egtviz.viewer.classroom.host import ClassroomHost
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.workbench.app import EgtvizApp

from _waiting import wait_until


@pytest.fixture
def classroom(tmp_path, monkeypatch):
    """``(app, host, progress, join)``, the class released to explore; ``join(name)`` connects one more tab, joins
    it and returns its client id and fake tab."""
    monkeypatch.setattr(host_module, "NAME_TIMEOUT", 0.05)  # a fake tab keeps no name: ask it at once
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    progress = ProgressStore(tmp_path / "progress.db")
    app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=progress)
    host = ClassroomHost(app)
    host.room.set_mode(Mode.EXPLORE)
    tabs: list[FakeTab] = []

    def join(name: str) -> tuple[int, FakeTab]:
        before = set(server.get_clients())
        tabs.append(FakeTab(server.get_port()))
        assert wait_until(lambda: set(server.get_clients()) - before, 30)
        (cid,) = set(server.get_clients()) - before
        time.sleep(0.3)  # the tab is asked for a name it does not keep, then shown the join page
        host.join(server.get_clients()[cid], name)
        assert wait_until(lambda: host.room.name_of(cid) == name and cid in app.views, 30)
        return cid, tabs[-1]

    yield app, host, progress, join
    for t in tabs:
        t.close()
    host.close()
    server.stop()
