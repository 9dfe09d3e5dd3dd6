"""A course served to a class on a real viser server, for the headless tests of the class on the course's pages."""

from __future__ import annotations

import pytest
import viser

from egtviz.classroom import Mode
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom import host as host_module
from egtviz.viewer.classroom.host import ClassroomHost
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.tabs import EgtvizApp

from _waiting import PATIENCE, wait_for


def watch_opened(host: ClassroomHost) -> set[int]:
    """The client ids of the tabs ``host`` has finished opening (a student's: asked for a name it keeps, then shown
    the join page), filled in as it does: a test joins a tab once its join page is up."""
    opened: set[int] = set()
    open_tab = host.open

    def opening(client):
        shown = open_tab(client)
        opened.add(client.client_id)
        return shown

    host.open = opening  # type: ignore[method-assign] - the app calls the host's open on each new tab
    return opened


def paced(host: ClassroomHost) -> None:
    """Wait until the class has moved the students' tabs for every pacing change made so far (it moves them in
    order, on one thread of its own): what a change did, or did not do, can then be checked."""
    host.gate._mover.submit(lambda: None).result(PATIENCE)


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
    opened = watch_opened(host)

    def join(name: str) -> tuple[int, FakeTab]:
        before = set(server.get_clients())
        tabs.append(FakeTab(server.get_port()))
        wait_for(lambda: set(server.get_clients()) - before, f"{name}'s tab to connect")
        (cid,) = set(server.get_clients()) - before
        wait_for(lambda: cid in opened, f"{name}'s tab to be asked for a name it does not keep, then shown the "
                 "join page")
        host.join(server.get_clients()[cid], name)
        wait_for(lambda: host.room.name_of(cid) == name and cid in app.views, f"{name} to join and get a workbench")
        return cid, tabs[-1]

    yield app, host, progress, join
    for t in tabs:
        t.close()
    host.close()
    server.stop()
