"""``egtviz serve``: start the viewer on a local port and block until Ctrl-C."""

from __future__ import annotations

import argparse
import sys
import threading
from pathlib import Path

__all__ = ["add_parser", "run", "serve", "start"]


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``serve`` sub-command on an ``argparse`` sub-parser set."""
    p = subparsers.add_parser("serve", help="start the interactive viewer in the browser",
                              description="Start the egtviz viewer (each browser tab gets its own scene).")
    add_arguments(p)
    p.set_defaults(func=run)
    return p


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this computer only)")
    p.add_argument("--port", type=int, default=8080, help="port (default 8080; 0 = any free port)")
    p.add_argument("--scene", metavar="FILE", default=None, help="start every tab from this scene: a JSON file saved by egtviz, or a built-in name "
                   "(default, panoramic, example1, example3)")
    p.add_argument("--demo", choices=["pinhole", "panoramic"], default=None,
                   help="open this visual-servoing demo in every new tab (docs/servo.md)")


def load_scene_argument(value: str | Path):
    """A scene file, or the name of a built-in scene (``default``, ``panoramic``, ``example1``, ``example3``)."""
    from ..scene import SCENES, Scene

    if str(value) in SCENES and not Path(value).exists():
        return SCENES[str(value)]()
    return Scene.load(value)


def start(host: str = "127.0.0.1", port: int = 8080, scene_path: str | Path | None = None, *, verbose: bool = False,
          demo: str | None = None):
    """Start a server and the app without blocking; returns ``(server, app)``.

    Raises:
        SceneFileError: the scene file cannot be read (the message names the file and entry).
    """
    import viser

    from ..scene import Scene
    from .app import EgtvizApp

    scene = load_scene_argument(scene_path) if scene_path is not None else None
    server = viser.ViserServer(host=host, port=port, verbose=verbose)
    app = EgtvizApp(server, scene, demo=demo)
    return server, app


def serve(host: str = "127.0.0.1", port: int = 8080, scene_path: str | Path | None = None,
          *, stop_event: threading.Event | None = None, demo: str | None = None) -> int:
    """Serve until Ctrl-C (or until ``stop_event`` is set); returns the exit status."""
    from ..scene import SceneFileError

    try:
        server, _app = start(host, port, scene_path, demo=demo)
    except SceneFileError as exc:
        print(f"egtviz: cannot read the scene file: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"egtviz: cannot start the server: {exc}", file=sys.stderr)
        return 1
    print(f"egtviz running at http://{host}:{server.get_port()}", flush=True)
    stop = stop_event or threading.Event()
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        print("egtviz: stopped", flush=True)
    finally:
        server.stop()
    return 0


def run(args: argparse.Namespace) -> int:
    """Entry point for the parsed ``serve`` sub-command."""
    return serve(args.host, args.port, args.scene, demo=getattr(args, "demo", None))


def main(argv: list[str] | None = None) -> int:
    """``python -m egtviz.viewer.cli [--host H] [--port P] [--scene FILE]``."""
    parser = argparse.ArgumentParser(prog="egtviz-serve")
    add_arguments(parser)
    args = parser.parse_args(argv)
    return run(args)


if __name__ == "__main__":
    raise SystemExit(main())
