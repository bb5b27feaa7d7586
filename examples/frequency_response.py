"""Frequency-response curves: the softening resonance of the pendulum, with hysteresis.
====================================================================================

The forcing frequency is swept up and then down; each point starts from the previous
point's final state. The linear model follows A / sqrt((w0^2 - W^2)^2 + (c W)^2) both
ways. The nonlinear pendulum's resonance bends towards lower frequency (its free
period grows with amplitude), so between the two folds two steady amplitudes coexist:
sweeping down rides the large one, sweeping up the small one, and each jumps at a
different frequency.

Usage::

    python examples/frequency_response.py [--points N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sweep
from sweep.maps.response import frequency_response


def compute(points: int):
    """Both models, g = L = 1, c = 0.02 1/s, A = 0.02 rad/s^2, W in [0.8, 1.1] rad/s."""
    frequencies = np.linspace(0.8, 1.1, points)
    curves = {}
    for model in ("linear", "nonlinear"):
        scene = sweep.Scene(gravity=1.0, length=1.0, model=model,
                            effects=(sweep.Damping(0.02), sweep.Forcing(0.02, 1.0)))
        curves[model] = frequency_response(scene, frequencies, periods_transient=150,
                                           periods_measure=10, steps_per_period=100)
    return curves


def main(argv=None) -> int:
    """Write frequency_response.png into the output folder."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=61, help="frequencies per sweep")
    parser.add_argument("--out", type=Path,
                        default=Path("examples/output/frequency_response"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    curves = compute(args.points)
    fig, ax = plt.subplots(figsize=(7.0, 4.6), layout="constrained")
    styles = {("linear", "up"): ("0.6", "-", None), ("linear", "down"): ("0.6", ":", None),
              ("nonlinear", "up"): ("tab:blue", "-", "^"),
              ("nonlinear", "down"): ("tab:red", "-", "v")}
    for model, curve in curves.items():
        for direction in ("up", "down"):
            color, line, marker = styles[(model, direction)]
            ax.plot(curve.forcing_frequency, np.degrees(curve.amplitude.sel(direction=direction)),
                    color=color, linestyle=line, marker=marker, markersize=3,
                    label=f"{model}, sweep {direction}")
    ax.set_xlabel("forcing angular frequency W [rad/s]  (natural frequency 1 rad/s)")
    ax.set_ylabel("steady amplitude [deg]")
    ax.set_title("Frequency response, c = 0.02 1/s, A = 0.02 rad/s²")
    ax.legend()
    sweep.plot.save_figure(fig, args.out / "frequency_response.png")
    up = curves["nonlinear"].amplitude.sel(direction="up").values
    down = curves["nonlinear"].amplitude.sel(direction="down").values
    window = curves["nonlinear"].forcing_frequency.values[np.abs(down - up) > 0.1]
    if window.size:
        print(f"hysteresis window: W in [{window.min():.3f}, {window.max():.3f}] rad/s")
    print(f"wrote {args.out / 'frequency_response.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
