"""Safe file I/O (``egtviz.files``): reads refuse devices, FIFOs, folders and big files before reading;
writes refuse non-regular targets, are atomic, and leave nothing behind on failure."""

import json
import os
import threading

import pytest

from egtviz.files import FileSafetyError, check_write_target, printable, read_limited, write_atomic
from egtviz.scene import SceneFileError, default_scene, load_scene_file, save_scene_file

from _threads import joined, returns


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_read_regular_file_and_symlink_to_one(tmp_path):
    f = tmp_path / "a.txt"
    f.write_bytes(b"hello")
    assert read_limited(f, 5) == b"hello"
    link = tmp_path / "link.txt"
    link.symlink_to(f)
    assert read_limited(link, 5) == b"hello"


def test_fifo_read_returns_at_once_with_an_error(tmp_path):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    # Nobody writes to the FIFO: a blocking open would hang (each call is made in a thread, and fails the test if
    # it has not returned within minutes).
    with pytest.raises(FileSafetyError, match="FIFO"):
        returns(lambda: read_limited(fifo, 1000), "read_limited of a FIFO to refuse it")
    with pytest.raises(SceneFileError, match="pipe.json: not a regular file"):
        returns(lambda: load_scene_file(fifo), "load_scene_file of a FIFO to refuse it")


def test_dev_zero_and_folders_and_links_to_them_are_refused(tmp_path):
    with pytest.raises(FileSafetyError, match="device"):
        read_limited("/dev/zero", 10**9)
    link = tmp_path / "zero.json"
    link.symlink_to("/dev/zero")
    with pytest.raises(FileSafetyError, match="device"):
        read_limited(link, 10**9)
    with pytest.raises(FileSafetyError, match="directory"):
        read_limited(tmp_path, 10**9)
    with pytest.raises(FileSafetyError, match="no such file"):
        read_limited(tmp_path / "missing.json", 10)


def test_oversized_file_refused_before_reading(tmp_path):
    f = tmp_path / "big.json"
    f.write_bytes(b" " * 101)
    with pytest.raises(FileSafetyError, match="limit"):
        read_limited(f, 100)
    assert read_limited(f, 101) == b" " * 101
    sparse = tmp_path / "sparse.json"
    with open(sparse, "wb") as fh:  # 3 GB by its size, nothing on disk: refused from the size alone
        fh.truncate(3 * 10**9)
    with pytest.raises(SceneFileError, match="3,000,000,000 bytes, more than the 2,000,000-byte limit"):
        load_scene_file(sparse)


def test_write_refuses_symlinks_devices_fifos_and_folders(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for bad, why in ((link, "symbolic link"), (fifo, "FIFO"), (tmp_path, "expected a file name|directory"),
                     ("/dev/null", "device"), (tmp_path / "sub" / "x.json", "does not exist")):
        with pytest.raises(FileSafetyError, match=why):
            write_atomic(bad, b"data")
    assert target.read_text() == "keep" and link.is_symlink()
    assert leftovers(tmp_path) == []
    with pytest.raises(FileSafetyError, match="exists already"):
        write_atomic(target, b"new", overwrite=False)
    assert target.read_text() == "keep"


def test_existing_regular_file_replaced_atomically_keeping_its_mode(tmp_path):
    f = tmp_path / "scene.json"
    f.write_text("old")
    os.chmod(f, 0o640)
    inode = f.stat().st_ino
    write_atomic(f, b"new")
    assert f.read_bytes() == b"new"
    assert f.stat().st_ino != inode  # a new file renamed over the old one, not rewritten in place
    assert f.stat().st_mode & 0o777 == 0o640
    assert leftovers(tmp_path) == []


def test_failed_write_leaves_no_temporary_file(tmp_path, monkeypatch):
    f = tmp_path / "scene.json"
    f.write_text("old")

    def broken_fsync(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(FileSafetyError, match="No space left"):
        write_atomic(f, b"new")
    assert f.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.json"]


def test_bad_folders_are_reported_before_any_work(tmp_path):
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    with pytest.raises(FileSafetyError, match="is not a folder"):
        check_write_target(plain / "x.json")
    with pytest.raises(FileSafetyError, match="does not exist"):
        check_write_target(tmp_path / "missing" / "x.json")
    with pytest.raises(FileSafetyError, match="expected a file name"):
        check_write_target("")
    with pytest.raises(FileSafetyError, match="cannot contain a NUL"):
        check_write_target(tmp_path / "a\0b.json")
    with pytest.raises(SceneFileError, match="cannot contain a NUL"):
        load_scene_file("a\0b.json")
    assert check_write_target(tmp_path / "new.json") == tmp_path / "new.json"


def test_concurrent_saves_to_one_name_never_give_a_corrupt_file(tmp_path):
    path = tmp_path / "shared.json"
    payloads = [json.dumps({"writer": i, "pad": "x" * (20_000 + 1000 * i)}).encode() for i in range(8)]
    errors = []
    seen = []
    stop = threading.Event()

    def writer(data):
        try:
            for _ in range(15):
                write_atomic(path, data)
        except Exception as exc:  # noqa: BLE001 - collected and asserted below
            errors.append(exc)

    def reader():
        while not stop.is_set():
            try:
                seen.append(path.read_bytes())
            except FileNotFoundError:
                pass

    r = threading.Thread(target=reader)
    r.start()
    threads = [threading.Thread(target=writer, args=(p,)) for p in payloads]
    for t in threads:
        t.start()
    for t in threads:
        joined(t, "a writer's 15 atomic writes")
    stop.set()
    joined(r, "the reader to stop")
    assert errors == []
    assert path.read_bytes() in payloads
    assert seen and all(s in payloads for s in seen)  # every read saw one whole version
    assert leftovers(tmp_path) == []


def test_scene_save_and_load_go_through_the_safe_functions(tmp_path):
    path = tmp_path / "s.json"
    save_scene_file(default_scene(), path)
    assert load_scene_file(path).to_dict() == default_scene().to_dict()
    link = tmp_path / "l.json"
    link.symlink_to(path)
    with pytest.raises(FileSafetyError, match="symbolic link"):
        save_scene_file(default_scene(), link)


def test_printable_escapes_control_characters():
    assert printable("plain name.json") == "plain name.json"
    assert printable("a\x1b[2Jb\x9bc\nd") == "a\\x1b[2Jb\\x9bc\\x0ad"
    assert printable("bidi\u202eevil") == "bidi\\u202eevil"
