"""Basin stability of a power grid: dead ends undermine it, new lines restore it.
================================================================================

The swing equation ``theta_i'' = P_i - alpha theta_i' + K sum_j A_ij sin(theta_j -
theta_i)`` of a grid of generators (P = 1) and consumers (P = -1), ``alpha = 0.1``,
``K = 8`` (``sweep.SwingNetwork``): a ring of six with a dead end (node 6, hanging off
node 0 by one line) and a dead tree (node 7 off node 1, nodes 8 and 9 off node 7). For
each node, random perturbations of its phase and frequency from the synchronous state;
its *single-node basin stability* is the fraction after which the whole grid is
synchronous again (Menck et al., Nat. Phys. 9, 89 (2013)), with its standard error.
The same grid with three lines that close the trees into the ring is more stable,
most of all at the trees' roots and inner nodes (Menck et al., Nat. Commun. 5, 3969
(2014)).

Usage::

    python examples/swing_basin_stability.py [--samples N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sweep

EDGES = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (0, 6), (1, 7), (7, 8), (7, 9)]
REPAIRS = [(6, 5), (8, 2), (9, 3)]
POWER = [1, -1, 1, -1, 1, -1, -1, 1, -1, 1]


def compute(samples: int):
    """Basin stability per node of the grid with its trees and of the repaired grid.

    Returns
    -------
    dict of xarray.Dataset
        ``{"with dead ends": ..., "repaired": ...}`` (`sweep.maps.basin_stability`).
    """
    results = {}
    for name, edges in (("with dead ends", EDGES), ("repaired", EDGES + REPAIRS)):
        network = sweep.SwingNetwork(edges, power=POWER, damping=0.1, coupling=8.0)
        results[name] = sweep.maps.basin_stability(network, samples, seed=1, t_end=200.0,
                                                   dt=0.005, delta_omega=(-30.0, 30.0))
    return results


def main(argv=None) -> int:
    """Print the table and write basin_stability.png into the output folder."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=500, help="perturbations per node")
    parser.add_argument("--out", type=Path, default=Path("examples/output/swing"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    results = compute(args.samples)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    width = 0.4
    for k, (name, bs) in enumerate(results.items()):
        nodes = bs.node.values
        ax.bar(nodes + (k - 0.5) * width, bs.basin_stability, width,
               yerr=bs.standard_error, capsize=2, label=name)
        print(f"{name}: " + ", ".join(f"{n}: {p:.3f} +- {e:.3f}" for n, p, e in zip(
            nodes, bs.basin_stability.values, bs.standard_error.values)))
    ax.set_xticks(np.arange(10))
    ax.set_xlabel("perturbed node (6: dead end; 7: root of 8, 9)")
    ax.set_ylabel("single-node basin stability")
    ax.set_ylim(0, 1.2)
    ax.set_yticks(np.linspace(0, 1, 6))
    ax.legend(loc="upper center", ncol=2, frameon=False)
    ax.set_title(f"Swing network, {args.samples} perturbations per node")
    fig.tight_layout()
    sweep.plot.save_figure(fig, args.out / "basin_stability.png")
    print(f"wrote {args.out / 'basin_stability.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
