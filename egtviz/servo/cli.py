"""``egtviz servo pinhole|panoramic``: run a servo simulation headless, print a summary, save JSON / PNG.

The lead wires :func:`add_parser` and :func:`run` into ``egtviz/cli.py``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from .result import ServoResult

ESTIMATOR_CHOICES = {"true": None, "linear": 1, "normalized": 2, "sampson": 3}


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register the ``servo`` sub-command on an argparse ``subparsers`` object; returns its parser."""
    p = subparsers.add_parser(
        "servo",
        help="run a visual-servoing simulation headless (EGT section 7)",
        description="Simulate the pin-hole arm (Rives' hybrid task) or the panoramic robot (bi-conics) servo.",
    )
    p.add_argument("demo", choices=["pinhole", "panoramic"], help="which demo to run")
    p.add_argument("--seed", type=int, default=0, help="seed of the start pose and the noise (default 0)")
    p.add_argument("--beta", type=float, default=1.0, help="pin-hole: weight of the translation task (default 1)")
    p.add_argument("--noise", type=float, default=0.0, metavar="PX", help="image noise, pixels (default 0)")
    p.add_argument(
        "--estimator",
        choices=list(ESTIMATOR_CHOICES),
        default="true",
        help="pin-hole: F from the true poses or estimated each step (default true)",
    )
    p.add_argument("--steps", type=int, default=None, help="maximum number of steps")
    p.add_argument("--json", metavar="FILE", default=None, help="write the full result as JSON")
    p.add_argument("--plot", metavar="FILE.png", default=None, help="write a PNG of feature trails, controls, errors")
    p.set_defaults(func=run)
    return p


def _simulate(args: argparse.Namespace, progress: Any) -> ServoResult:
    kwargs: dict[str, Any] = {"seed": args.seed, "noise_px": args.noise, "progress": progress}
    if args.steps is not None:
        kwargs["steps"] = args.steps
    if args.demo == "pinhole":
        from .pinhole_arm import simulate_pinhole

        return simulate_pinhole(beta=args.beta, f_algorithm=ESTIMATOR_CHOICES[args.estimator], **kwargs)
    from .panoramic_robot import simulate_panoramic

    return simulate_panoramic(**kwargs)


def run(args: argparse.Namespace) -> int:
    """Run the sub-command: 0 when the run converged, 1 when it did not, 2 on invalid parameters."""
    if args.noise is not None and (not math.isfinite(args.noise) or args.noise < 0):
        print(f"egtviz servo: error: --noise must be a finite number of pixels >= 0, got {args.noise}", file=sys.stderr)
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
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result.to_json_dict(), fh, allow_nan=False)
    if args.plot:
        plot_result(result, args.plot)
    return 0 if result.converged else 1


def plot_result(result: ServoResult, path: str) -> None:
    """Write a PNG: feature trails in the image, the controls and the errors over time (matplotlib, Agg)."""
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
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry point (``python -m egtviz.servo.cli pinhole ...``)."""
    parser = argparse.ArgumentParser(prog="egtviz")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["servo", *(argv if argv is not None else sys.argv[1:])])
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
