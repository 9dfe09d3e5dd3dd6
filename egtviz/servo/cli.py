"""``egtviz servo pinhole|panoramic``: run a servo simulation headless, print a summary, save JSON / PNG.

The lead wires :func:`add_parser` and :func:`run` into ``egtviz/cli.py``.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import sys
from typing import Any

from ..files import FileSafetyError, check_write_target, printable, write_atomic
from ..scene.limits import SERVO_HEADLESS_STEPS
from .result import ServoResult

ESTIMATOR_CHOICES = {"true": None, "linear": 1, "normalized": 2, "sampson": 3}


MAX_NOISE_PX = 100.0
MAX_BETA = 1e3
MAX_SEED = 2**63 - 1
_PINHOLE_ONLY = ("beta", "estimator")


def whole_number_in(low: int, high: int):
    """An argparse type: a whole number in ``low..high`` (``1e9`` and ``2.5`` are refused)."""

    def parse(text: str) -> int:
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number in {low}..{high}, got {text!r:.40}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a whole number in {low}..{high}, got {value}")
        return value

    parse.__name__ = "whole number"
    return parse


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register the ``servo`` sub-command on an argparse ``subparsers`` object; returns its parser."""
    p = subparsers.add_parser(
        "servo",
        help="run a visual-servoing simulation headless (EGT section 7)",
        description="Simulate the pin-hole arm (Rives' hybrid task) or the panoramic robot (bi-conics) servo; "
        "print a summary and optionally write the run as JSON and a PNG plot. Options marked 'pin-hole' are "
        "refused for the panoramic demo. Exit status: 0 converged, 1 did not converge or an output could not "
        "be written, 2 a refused option.",
    )
    p.add_argument("demo", choices=["pinhole", "panoramic"], help="which demo to run")
    p.add_argument("--seed", type=whole_number_in(0, MAX_SEED), default=0,
                   help="seed of the start pose and the noise, a whole number >= 0 (default 0)")
    p.add_argument("--beta", type=float, default=None,
                   help=f"pin-hole: weight of the translation task, 0..{MAX_BETA:g} (default 1)")
    p.add_argument("--noise", type=float, default=0.0, metavar="PX",
                   help=f"image noise, pixels, 0..{MAX_NOISE_PX:g} (default 0)")
    p.add_argument(
        "--estimator",
        choices=list(ESTIMATOR_CHOICES),
        default=None,
        help="pin-hole: F from the true poses or estimated each step (default true)",
    )
    steps = SERVO_HEADLESS_STEPS
    p.add_argument("--steps", type=whole_number_in(int(steps.low), int(steps.high)), default=None,
                   help=f"maximum number of steps, {steps.describe()} (default: the demo's own)")
    p.add_argument("--json", metavar="FILE", default=None,
                   help="write the full result as JSON (atomically; an existing regular file is replaced)")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write a PNG of feature trails, controls and errors (atomically)")
    p.set_defaults(func=run)
    return p


def _simulate(args: argparse.Namespace, progress: Any) -> ServoResult:
    kwargs: dict[str, Any] = {"seed": args.seed, "noise_px": args.noise, "progress": progress}
    if args.steps is not None:
        kwargs["steps"] = args.steps
    if args.demo == "pinhole":
        from .pinhole_arm import simulate_pinhole

        beta = 1.0 if args.beta is None else args.beta
        return simulate_pinhole(beta=beta, f_algorithm=ESTIMATOR_CHOICES[args.estimator or "true"], **kwargs)
    from .panoramic_robot import simulate_panoramic

    return simulate_panoramic(**kwargs)


def _refusal(args: argparse.Namespace) -> str | None:
    """Why these options cannot run (checked before the simulation), or None."""
    if args.demo != "pinhole":
        for name in _PINHOLE_ONLY:
            if getattr(args, name, None) is not None:
                return f"--{name} is a pin-hole option; the {args.demo} demo does not use it"
    for name, high, unit in (("beta", MAX_BETA, ""), ("noise", MAX_NOISE_PX, " px")):
        value = getattr(args, name, None)
        if value is not None and not (math.isfinite(value) and 0.0 <= value <= high):
            return f"--{name}: expected a number in 0..{high:g}{unit}, got {value:g}"
    if args.plot is not None and not str(args.plot).lower().endswith(".png"):
        return f"--plot writes a PNG: expected a file name ending in .png, got '{printable(args.plot)}'"
    outputs = [o for o in (args.json, args.plot) if o is not None]
    if len(outputs) == 2 and os.path.abspath(outputs[0]) == os.path.abspath(outputs[1]):
        return "--json and --plot name the same file"
    try:
        for target in outputs:
            check_write_target(target)
    except FileSafetyError as exc:
        return f"cannot write the output: {exc}"
    return None


def run(args: argparse.Namespace) -> int:
    """Run the sub-command: 0 when the run converged, 1 when it did not (or an output could not be written),
    2 on refused options (checked before the simulation starts)."""
    refused = _refusal(args)
    if refused is not None:
        print(f"egtviz servo: error: {refused}", file=sys.stderr)
        return 2
    from tqdm import tqdm

    bar = tqdm(total=args.steps, desc=f"servo {args.demo}", unit="step", file=sys.stderr, leave=False)

    def progress(k: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.n = k
        bar.refresh()

    try:
        result = _simulate(args, progress)
    except ValueError as exc:
        bar.close()
        print(f"egtviz servo: error: {exc}", file=sys.stderr)
        return 2
    bar.close()
    print(result.summary())
    try:
        if args.json:
            data = json.dumps(result.to_json_dict(), allow_nan=False).encode("utf-8")
            write_atomic(args.json, data)
        if args.plot:
            write_atomic(args.plot, plot_png(result))
    except (FileSafetyError, ValueError) as exc:
        print(f"egtviz servo: error: cannot write the output: {exc}", file=sys.stderr)
        return 1
    return 0 if result.converged else 1


def plot_png(result: ServoResult) -> bytes:
    """The bytes of :func:`plot_result`'s PNG."""
    buf = io.BytesIO()
    plot_result(result, buf)
    return buf.getvalue()


def plot_result(result: ServoResult, path: Any) -> None:
    """Write a PNG: feature trails in the image, the controls and the errors over time (matplotlib, Agg).

    ``path`` is a file name or a binary file object (the command line writes through :func:`plot_png`).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    ax = axes[0, 0]
    W, H = result.params.get("image_size", [640, 480])
    for i in range(result.features.shape[1]):
        ax.plot(result.features[:, i, 0], result.features[:, i, 1], lw=0.8)
        ax.plot(*result.features[0, i], "o", ms=3, color="0.4")
    ax.plot(result.desired_features[:, 0], result.desired_features[:, 1], "x", color="k", label="desired")
    ax.set_xlim(0, W)
    ax.set_ylim(H, 0)
    ax.set_aspect("equal")
    ax.set_title("feature trails (o start, x desired)")
    ax.legend(loc="lower right")
    t = result.time
    ax = axes[0, 1]
    if result.demo == "pinhole":
        tw = result.controls["camera_twist"]
        for j, name in enumerate(["vx", "vy", "vz", "wx", "wy", "wz"]):
            ax.plot(t, tw[:, j], label=name)
        ax.set_title("camera twist (camera frame)")
        ax2 = axes[1, 1]
        qd = result.controls["joint_velocities"]
        for j in range(qd.shape[1]):
            ax2.plot(t, qd[:, j], label=f"qd{j + 1}")
        ax2.set_title("joint velocities (rad/s)")
        ax2.legend(fontsize=7)
    else:
        u = result.controls["robot_velocity"]
        for j, name in enumerate(["v_x", "v_y", "omega"]):
            ax.plot(t, u[:, j], label=name)
        ax.set_title("robot inputs (robot frame)")
        ax2 = axes[1, 1]
        ax2.plot(t, result.extras["s_px"], label="s(t) px")
        ax2.set_yscale("log")
        ax2.set_title("feature distance s(t)")
        ax2.legend(fontsize=7)
    ax.legend(fontsize=7)
    ax.set_xlabel("t (s)")
    ax = axes[1, 0]
    for name in ("rotation_error_rad", "translation_error", "task_error_norm"):
        if name in result.errors:
            ax.semilogy(t, np.maximum(np.abs(result.errors[name]), 1e-16), label=name)
    ax.set_title("errors")
    ax.set_xlabel("t (s)")
    ax.legend(fontsize=7)
    fig.suptitle(result.summary()[:150], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90, format="png")
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry point (``python -m egtviz.servo.cli pinhole ...``)."""
    parser = argparse.ArgumentParser(prog="egtviz")
    add_parser(parser.add_subparsers(dest="command", required=True))
    try:
        args = parser.parse_args(["servo", *(argv if argv is not None else sys.argv[1:])])
    except SystemExit as exc:  # usage error (2) or --help (0)
        return int(exc.code or 0)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
