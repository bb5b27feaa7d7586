"""The ``sweep`` command: a thin shell over the Python API.

::

    sweep run RUN.toml -o OUT.nc [--checkpoint DIR] [--resume] [--scheduler ADDRESS]
                                 [--no-space-check] [--progress | --no-progress]
    sweep demo [-o FOLDER] [--size N]
    sweep plot FILE.nc --var NAME [--sel DIM=VALUE ...] -o OUT.png
    sweep plot FILE.nc --trajectory --sel theta0=VALUE --sel omega0=VALUE -o OUT.png
    sweep fractions FILE.nc [--label NAME] [--convergence] [-o OUT.csv]
    sweep map-accuracy RUN.toml --ladder KEY=V1,V2,... [--label NAME] [--repeats N]
                       [--pilot N] [-o OUT.nc] [--figure OUT.png]
    sweep explore [RUN.toml] [--port N] [--host ADDRESS] [--device cpu|cuda] [--no-browser]
    sweep --version

Every error is one line on stderr, ``sweep: error: ...``, and exit status 2, those of
the argument parser too (`_Parser`: an unknown option is named first, with the nearest
valid one); no output file is written when a command fails. ``sweep run`` stopped by
Ctrl-C (SIGINT) exits with 130, by SIGTERM (how batch systems stop a job) with 143,
after one line that says how to resume. A command whose stdout is closed early
(``sweep fractions FILE.nc | head``) ends quietly with 141, as one SIGPIPE ended.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import math
import os
import re
import signal
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np

from ._version import __version__
from .kernels.spec import DEVICES, DTYPES

__all__ = ["DEMO", "build_parser", "main"]

#: Exit status of every error (the same as argparse's usage errors).
EXIT_ERROR = 2

#: Exit status of a command whose stdout was closed before it ended (``sweep fractions
#: FILE.nc | head``): 128 + 13 (SIGPIPE), what a shell reports for ``cat``, ``yes`` or
#: any tool SIGPIPE ended; quiet, as theirs (``set -o pipefail`` sees it).
EXIT_BROKEN_PIPE = 128 + 13

#: Exit status of ``sweep run`` stopped by Ctrl-C (SIGINT): 128 + 2, as a shell reports.
EXIT_INTERRUPTED = 130

#: Exit status of ``sweep run`` stopped by SIGTERM: 128 + 15, what a shell or a batch
#: system reports for a process that signal ended.
EXIT_TERMINATED = 128 + int(signal.SIGTERM)

#: Seconds ``sweep run`` waits after SIGTERM or Ctrl-C for the chunk being computed to
#: end (a chunk boundary) before it stops without it (`_Stop`). Chunks last about a
#: second by default; Slurm sends SIGKILL 30 s after SIGTERM by default (KillWait), as
#: Kubernetes does (terminationGracePeriodSeconds), so the process is gone well before.
TERMINATE_WAIT_S = 10.0

#: The demo sweep: a damped, unforced, nonlinear pendulum over the phase plane.
#: With c = 0.3 1/s the energy decays by exp(-c t) ~ 6e-6 by t_end = 40 s, so every
#: trajectory has settled in a well; winding and well index do not change between
#: dt = 0.05 and dt = 0.005 on the 301 x 301 grid.
DEMO = {
    "gravity": 9.81,          # m/s^2
    "length": 1.0,            # m
    "damping": 0.3,           # 1/s
    "theta0": (-math.pi, math.pi),   # rad
    "omega0": (-10.0, 10.0),  # rad/s; about 3 full turns at the edges
    "t_end": 40.0,            # s
    "dt": 0.04,               # s
    "observe": ("final", "winding", "capture", "energy"),
    "size": 301,              # grid points per axis
}


# ------------------------------------------------------------------------------ parser
class _UsageError(Exception):
    """An error of the command line as `_Parser` found it (``parser``: the parser of the
    command or sub-command that found it, ``message``: argparse's words)."""

    def __init__(self, parser: argparse.ArgumentParser, message: str) -> None:
        super().__init__(message)
        self.parser, self.message = parser, message


class _Parser(argparse.ArgumentParser):
    """An `argparse.ArgumentParser` whose usage errors raise `_UsageError` instead of
    printing the usage block and exiting, so that `main` says them in one ``sweep:
    error:`` line (`_usage_message`); ``--help`` and ``--version`` are unchanged."""

    def error(self, message: str):
        raise _UsageError(self, message)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``sweep`` command (sub-commands run, demo, plot,
    explore)."""
    parser = _Parser(
        prog="sweep",
        description="JIT-compiled parameter sweeps of pendulum dynamics.",
    )
    parser.add_argument("--version", action="version", version=f"sweep {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    parser.commands = commands.choices  # name -> parser, for _usage_message

    run = commands.add_parser("run", help="run the sweep a TOML run file describes",
                              description="Run the sweep described by a TOML run file "
                              "(tables [scene], [grid], [run]) and save it as netCDF.")
    run.add_argument("run_file", metavar="RUN.toml", help="the run file")
    run.add_argument("-o", "--output", required=True, metavar="OUT.nc",
                     help="netCDF file to write (its folder must exist)")
    run.add_argument("--checkpoint", metavar="DIR",
                     help="write each finished chunk to the folder DIR (created if missing) "
                     "so that an interrupted run can be resumed with --resume (default with "
                     "--resume: OUT.nc.checkpoint); removed once OUT.nc is written")
    run.add_argument("--resume", action="store_true",
                     help="continue the interrupted run whose checkpoint is in DIR: finished "
                     "chunks are loaded, not recomputed, and OUT.nc is bit-identical to an "
                     "uninterrupted run (a checkpoint of a different run is refused). With "
                     "no checkpoint in DIR the run starts from the beginning, after a note "
                     "on stderr, so the same command starts a batch job and resumes it")
    run.add_argument("--scheduler", metavar="ADDRESS",
                     help="run the chunks on the Dask cluster of this scheduler "
                     "(tcp://HOST:8786; overrides [run] scheduler); needs the dask extra. "
                     "Results are bit-identical to a local run; --checkpoint/--resume work "
                     "the same")
    run.add_argument("--device", choices=DEVICES,
                     help="where to run: the CPU (default) or an NVIDIA GPU (needs the cuda "
                     "extra); overrides [run] device")
    run.add_argument("--pilot", type=int, metavar="N",
                     help="forced maps: first run N x N starts of the grid with early stop "
                     "to find the attractors, then stop each trajectory of the map once it "
                     "follows one (sweep.maps.pilot_catalogue; the grid may vary only "
                     "theta0 and omega0; a driven [system]'s map observes 'attractor' and "
                     "varies only the initial state); overrides [run] pilot")
    run.add_argument("--dtype", choices=DTYPES,
                     help="working precision of the state and the step (float32: "
                     "float32 rounding, and 1.28-1.33x float64's trajectories per second "
                     "with the nonlinear pendulum, 1.69x with the linear model, on a "
                     "2-core AMD EPYC Zen 5 (2026-11-25); not measured on Intel since "
                     "0.3; no faster on an H100; fixed-step methods); overrides [run] "
                     "dtype")
    run.add_argument("--no-space-check", action="store_true",
                     help="run even if OUT.nc (and the checkpoint) may not fit in the free "
                     "space: the check bounds the file by its uncompressed size, and the "
                     "file is compressed (usually 1.6-2.7x smaller). A file that does not "
                     "fit after all fails when it is written, leaving no partial file; with "
                     "--checkpoint the computed chunks stay")
    _progress_option(run)
    run.set_defaults(handler=_command_run)

    demo = commands.add_parser(
        "demo", help="sweep the damped pendulum over the phase plane and draw maps",
        description="Sweep a damped pendulum (c = 0.3 1/s, g/L = 9.81 1/s^2) over "
        "theta0 in [-180, 180] deg and omega0 in [-10, 10] rad/s, write it as demo.nc "
        "and draw two maps: the well each start is captured in (well.png) and the time "
        "until it is captured (capture_time.png).")
    demo.add_argument("-o", "--output", default="sweep-demo", metavar="FOLDER",
                      help="folder for demo.nc and the PNG maps (created if missing; "
                      "default: %(default)s)")
    demo.add_argument("--size", type=int, default=DEMO["size"], metavar="N",
                      help="grid points per axis, N >= 2 (default: %(default)s)")
    _progress_option(demo)
    demo.set_defaults(handler=_command_demo)

    plot = commands.add_parser(
        "plot", help="draw a 2-D map of a variable, or a trajectory",
        description="Draw a 2-D map of a data variable, or theta(t) and the phase "
        "portrait of a sampled trajectory, from a netCDF file written by sweep.")
    plot.add_argument("file", metavar="FILE.nc", help="netCDF file written by sweep")
    what = plot.add_mutually_exclusive_group(required=True)
    what.add_argument("--var", metavar="NAME", help="data variable to map")
    what.add_argument("--trajectory", action="store_true",
                      help="draw theta(t) and the phase portrait (needs a 'time' dimension: "
                      "a run with save_every)")
    what.add_argument("--orbit-diagram", metavar="AXIS",
                      help="draw the stroboscopic angles against the grid axis AXIS (needs "
                      "a run observing strobe; more samples: [run] strobe_samples)")
    plot.add_argument("--sel", action="append", default=[], metavar="DIM=VALUE",
                      help="select the grid point VALUE along DIM; VALUE in the file's "
                      "units (rad, rad/s, ...) or in degrees with a 'deg' suffix "
                      "(theta0=-120deg), a value of the axis (within 1 %% of its "
                      "spacing; another is refused); repeat for several dimensions")
    plot.add_argument("-o", "--output", required=True, metavar="OUT.png",
                      help="image file to write (its folder must exist)")
    plot.add_argument("--radians", action="store_true",
                      help="draw the angle axes (theta0 and omega0, a system's angles and "
                      "angular velocities, pivot_phase: sweep.plot.angle_axis) in rad and "
                      "rad/s instead of degrees")
    plot.add_argument("--cmap", metavar="NAME", help="matplotlib colormap")
    plot.set_defaults(handler=_command_plot)

    fractions = commands.add_parser(
        "fractions", help="the fraction of trajectories each label takes, with errors",
        description="Label the trajectories of a netCDF file written by sweep (a map of "
        "sweep.maps, or a variable) and print the fraction each label takes with its "
        "standard error (sweep.maps.fractions: basin stability; binomial for random "
        "samples, conservative for Sobol samples).")
    fractions.add_argument("file", metavar="FILE.nc", help="netCDF file written by sweep")
    fractions.add_argument("--label", default="basins", metavar="NAME",
                           help="basins (default), motion, well, period, inverted, or a "
                           "variable of the file")
    fractions.add_argument("--convergence", action="store_true",
                           help="also the estimates over the first 16, 32, ... trajectories "
                           "(sampled points; a grid's is refused)")
    fractions.add_argument("-o", "--output", metavar="OUT.csv",
                           help="also write the table as CSV (its folder must exist)")
    fractions.set_defaults(handler=_command_fractions)

    accuracy = commands.add_parser(
        "map-accuracy", help="how many of a map's labels each setting changes, and its cost",
        description="Run the starts of a run file ([sample] points cost seconds) under a "
        "ladder of settings and print, per setting, the fraction of starts whose label "
        "differs from the most accurate run (with its binomial standard error for sampled "
        "starts), the largest shift of a label's fraction, and the cost "
        "(sweep.map_accuracy). Each ladder varies one setting, the others at their most "
        "accurate (the last value of their ladder).")
    accuracy.add_argument("run_file", metavar="RUN.toml", help="the run file (its [run] "
                          "table: the settings every level shares)")
    accuracy.add_argument("--ladder", action="append", default=[], required=True,
                          metavar="KEY=V1,V2,...",
                          help="a setting and its values, least to most accurate (the last "
                          "is the reference): dt, t_end, t_transient (s), tol, rtol, "
                          "dtype (float32,float64) or method (heun,rk4); repeat for "
                          "several settings")
    accuracy.add_argument("--label", default="basins", metavar="NAME",
                          help="basins (default), motion, well, period, inverted, or a "
                          "variable of the run")
    accuracy.add_argument("--repeats", type=int, default=1, metavar="N",
                          help="wall time: best of N runs per level (default: %(default)s)")
    accuracy.add_argument("--pilot", type=int, metavar="N",
                          help="forced basins with stop_early: catalogue the attractors on "
                          "N x N starts first (default: [run] pilot, else 41)")
    accuracy.add_argument("-o", "--output", metavar="OUT.nc",
                          help="also write the table, the fractions and every start's "
                          "labels as netCDF (its folder must exist)")
    accuracy.add_argument("--figure", metavar="OUT.png",
                          help="also draw the labels differing against the wall time, "
                          "log-log (sweep.plot.map_accuracy)")
    accuracy.set_defaults(handler=_command_map_accuracy)

    boundary = commands.add_parser(
        "boundary", help="is a map's boundary fractal, and Wada? its numbers, one call",
        description="Run a run file's 2-D grid of theta0 x omega0, label it and print "
        "what the map's boundary is (sweep.maps.describe_boundary): each basin's fraction, "
        "the basin entropy Sb and Sbb, the fractality test (Puy et al. 2021), the "
        "uncertainty exponent at the grid's scale and, on request, below it (random "
        "pairs of starts, --sampled) and the Wada test (grid method, --wada). Forced "
        "basins are labelled by an attractor catalogue of a pilot grid, so new "
        "trajectories number the basins as the map does; an unforced map's basins are "
        "its wells.")
    boundary.add_argument("run_file", metavar="RUN.toml",
                          help="the run file: a [grid] of theta0 and omega0 (other axes "
                          "one value)")
    boundary.add_argument("--label", default="basins", metavar="NAME",
                          help="basins (default), motion, well, period or inverted")
    boundary.add_argument("--sampled", type=int, default=0, metavar="N",
                          help="the uncertainty exponent below the grid's scale from N "
                          "random pairs per eps level, eps 1e-9 to 1e-2 of the box "
                          "(>= 100; default: not computed)")
    boundary.add_argument("--wada", type=int, default=0, metavar="STEPS",
                          help="the Wada test with STEPS refinement steps (a map of three "
                          "basins or more; default: not computed)")
    boundary.add_argument("--pilot", type=int, metavar="N",
                          help="forced basins: catalogue the attractors on N x N starts "
                          "first (default: [run] pilot, else 41)")
    boundary.add_argument("--seed", type=int, default=0, metavar="S",
                          help="seed of the random balls and pairs (default: 0)")
    boundary.add_argument("-o", "--output", metavar="OUT.json",
                          help="also write the numbers as JSON (its folder must exist)")
    boundary.set_defaults(handler=_command_boundary)

    explore = commands.add_parser(
        "explore", help="explore maps in the browser, recomputed on every zoom",
        description="Start a local web app (sweep.explore; needs the explore extra) that "
        "draws any map of the scene over any two axes and recomputes the visible window on "
        "every zoom; print its URL. Without RUN.toml: the demo scene.")
    explore.add_argument("run_file", nargs="?", metavar="RUN.toml",
                         help="start from this run file's scene, axes and run settings "
                         "(default: the demo scene of sweep demo)")
    explore.add_argument("--port", type=int, default=0,
                         help="TCP port (default: a free one)")
    explore.add_argument("--host", default="127.0.0.1",
                         help="address to bind (default: %(default)s; any other lets anyone "
                         "who can reach the port use this machine's cores)")
    explore.add_argument("--device", choices=DEVICES,
                         help="where maps run (default: the run file's, else cpu)")
    explore.add_argument("--no-browser", action="store_true",
                         help="print the URL without opening a browser")
    explore.set_defaults(handler=_command_explore)
    return parser


def _progress_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="show a progress bar on stderr (default: when stderr is a "
                        "terminal and CI is not set)")


# ------------------------------------------------------------------------------- main
def main(argv: list[str] | None = None) -> int:
    """Run the ``sweep`` command.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit status: 0 on success, 2 on any error (one line on stderr starting
        ``sweep: error:``), 130 when interrupted (Ctrl-C), 143 when ``sweep run`` is
        stopped by SIGTERM, 141 (`EXIT_BROKEN_PIPE`) when stdout was closed before the
        command ended.
    """
    try:
        return _main(sys.argv[1:] if argv is None else list(argv))
    except BrokenPipeError:  # stdout closed early (sweep fractions ... | head)
        return _stdout_closed()


def _main(argv: list[str]) -> int:
    """`main`, less the closed stdout."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        return _error(_usage_message(parser, argv, exc))
    except SystemExit as exc:  # --help, --version (argparse printed them)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    try:
        status = args.handler(args)
        sys.stdout.flush()  # a closed stdout raises here, not at the interpreter's exit
        return status
    except BrokenPipeError:
        raise
    except (ValueError, TypeError, OSError) as exc:
        return _error(exc)
    except KeyboardInterrupt:
        print("sweep: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _stdout_closed() -> int:
    """End quietly once stdout's reader has gone (``| head``): what Python's documentation
    recommends (note on SIGPIPE in the `signal` module): point stdout at os.devnull, so
    that the interpreter's last flush of what is still buffered does not fail again.
    Returns `EXIT_BROKEN_PIPE`."""
    with contextlib.suppress(OSError, ValueError, AttributeError):  # no file descriptor
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    return EXIT_BROKEN_PIPE


def _usage_message(parser: argparse.ArgumentParser, argv: list[str],
                   exc: _UsageError) -> str:
    """The one line of an error the parser found: an option no parser knows first (it
    also explains a missing required one: a misspelled ``--outptu``), with the nearest
    valid option when one is close (`difflib`); else argparse's own words (an invalid
    choice names the choices), with what is accepted where argparse does not say."""
    commands = getattr(parser, "commands", {})
    where = next((i for i, a in enumerate(argv) if not a.startswith("-")), len(argv))
    command = argv[where] if where < len(argv) else None
    scans = [(parser, argv[:where])]
    if command in commands:
        scans.append((commands[command], argv[where + 1:]))
    for owner, tokens in scans:
        unknown = _unknown_options(owner, tokens)
        if unknown:
            name = unknown[0].split("=", 1)[0]
            options = sorted(o for o in owner._option_string_actions if o.startswith("--"))
            close = difflib.get_close_matches(name, options, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]}?" if close else ""
            words = "option" if len(unknown) == 1 else "options"
            prefix = "" if owner is parser else f"{owner.prog}: "
            return (f"{prefix}unrecognized {words} {', '.join(unknown)}{hint} "
                    f"(accepted: the options {owner.prog} --help lists)")
    message = exc.message
    if command is not None and command not in commands and "invalid choice" in message:
        close = difflib.get_close_matches(command, list(commands), n=1, cutoff=0.6)
        if close:
            message += f"; did you mean {close[0]}?"
    elif command is None and "required: COMMAND" in message:
        message += f"; accepted: {', '.join(commands)}"
    elif "invalid int value" in message:
        message += "; accepted: an integer"
    elif message.startswith("unrecognized arguments") and command in commands:
        owner = commands[command]  # an extra positional: what the command takes
        takes = [("at most one " if a.nargs == "?" else "one ") + str(a.metavar or a.dest)
                 for a in owner._actions if not a.option_strings]
        what = f"{' and '.join(takes)} and" if takes else "no argument but"
        return f"{owner.prog}: {message}; accepted: {what} the options {owner.prog} --help lists"
    prog = exc.parser.prog
    return message if prog == parser.prog else f"{prog}: {message}"


def _unknown_options(parser: argparse.ArgumentParser, tokens: list[str]) -> list[str]:
    """The tokens that look like options (``-x``, ``--name``, ``--name=value``) but are
    none of ``parser``'s, nor an abbreviation of one (argparse accepts a unique prefix
    and names the options an ambiguous one could be); negative numbers and what follows
    ``--`` are values."""
    known = parser._option_string_actions
    unknown = []
    for token in tokens:
        if token == "--":
            break
        if not token.startswith("-") or token == "-" or _NUMBER.match(token):
            continue
        if token.startswith("--"):
            name = token.split("=", 1)[0]
            prefixed = [o for o in known if o.startswith("--") and o.startswith(name)]
            if name in known or prefixed:  # several: argparse names the ambiguity
                continue
        elif token[:2] in known:  # -o, -oFILE
            continue
        unknown.append(token)
    return unknown


#: What argparse takes for a negative number rather than an option (``-1``, ``-0.5``).
_NUMBER = re.compile(r"^-\d+$|^-\d*\.\d+$")


def _error(exc: BaseException | str) -> int:
    """Print ``exc`` as one ``sweep: error:`` line on stderr; return the exit status."""
    message = " ".join(str(exc).split()) or type(exc).__name__
    print(f"sweep: error: {message}", file=sys.stderr)
    return EXIT_ERROR


def _run_quietly(scene, grid, **kwargs):
    """`sweep.run`, turning its warnings into ``sweep: warning:`` lines on stderr.

    Returns the dataset and the wall time in seconds (compile time included).
    """
    from .engine import run

    start = time.perf_counter()
    with _warnings_as_lines():
        ds = run(scene, grid, **kwargs)
    return ds, time.perf_counter() - start


@contextlib.contextmanager
def _warnings_as_lines():
    """Record the warnings raised in the block; once it has ended without an exception,
    print each as one ``sweep: warning:`` line on stderr."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for warning in caught:
        print(f"sweep: warning: {' '.join(str(warning.message).split())}", file=sys.stderr)


def _shape(grid) -> str:
    """``theta0 3 x omega0 4``; for points ``12 points of theta0, omega0``."""
    if grid.dims == ("point",):
        return f"{grid.size} points of {', '.join(grid.axes)}"
    return " x ".join(f"{name} {size}" for name, size in zip(grid.dims, grid.shape))


def _client(args: argparse.Namespace, options: dict):
    """The Dask client of ``--scheduler`` or ``[run] scheduler``; None without one."""
    scheduler = args.scheduler if args.scheduler is not None else options.get("scheduler")
    return _connect(scheduler) if scheduler is not None else None


def _stopped(exc: KeyboardInterrupt) -> tuple[str, int]:
    """How a run stopped by Ctrl-C or SIGTERM (`Terminated`) says so: the word and the
    exit status."""
    if isinstance(exc, Terminated):
        return "terminated", EXIT_TERMINATED
    return "interrupted", EXIT_INTERRUPTED


def _summary(ds, grid, seconds: float) -> str:
    """``12 trajectories (theta0 3 x omega0 4) in 0.52 s, 0 non-finite``; for points
    ``12 trajectories (12 points of theta0, omega0) ...``."""
    from .kernels import Status

    failed = int(np.count_nonzero(ds.status.values != Status.OK))
    return (f"{grid.size} trajectories ({_shape(grid)}) in {seconds:.2f} s wall time, "
            f"{failed} non-finite")


def _pilot_summary(scene, grid, pilot: int, catalogue: dict, seconds: float) -> str:
    """``pilot: 144 trajectories (theta1_0 12 x theta2_0 12) in 0.31 s wall time, 5
    attractors catalogued``: the pilot's grid (`sweep.maps.pilot.pilot_grid`), its
    time [s] (the pilot's run and its catalogue) and the attractors it found."""
    from .maps.pilot import pilot_grid
    from .physics.system import System

    thinned = pilot_grid(grid, pilot, scene if isinstance(scene, System) else None)
    found = len(catalogue["period"])
    return (f"pilot: {thinned.size} trajectories ({_shape(thinned)}) in {seconds:.2f} s "
            f"wall time, {found} attractor{'' if found == 1 else 's'} catalogued")


# -------------------------------------------------------------------------------- run
def default_checkpoint(output) -> Path:
    """The checkpoint folder ``sweep run`` uses when ``--resume`` is given without
    ``--checkpoint``: ``OUT.nc.checkpoint`` next to the output file."""
    output = Path(output)
    return output.with_name(output.name + ".checkpoint")


def _command_run(args: argparse.Namespace) -> int:
    """``sweep run``: read the run file, check the output path and the free space, run,
    save atomically.

    With ``--checkpoint``/``--resume`` each finished chunk is kept in the checkpoint
    folder until the output file is saved; Ctrl-C then exits with status 130, SIGTERM
    with 143 (`_Stop`), each with one line that says how to resume. If the output
    file cannot be written (a full disk), the line says how to write it from the
    checkpoint, elsewhere if need be, without recomputing. The output file is only
    ever written whole, at the end.
    """
    from .diskspace import check_space
    from .execution import checkpoint as _checkpoint
    from .io import check_output_path, save
    from .toml_spec import load_run

    _netcdf_name("-o", args.output)
    options = {}
    scene, grid, kwargs = load_run(args.run_file, options)
    output = check_output_path(args.output)
    folder = None
    if args.checkpoint is not None or args.resume:
        folder = Path(args.checkpoint) if args.checkpoint is not None else \
            default_checkpoint(output)
        kwargs.update(checkpoint=folder, resume=args.resume, keep_checkpoint=True)
    if args.device is not None:
        kwargs["device"] = args.device
    if args.dtype is not None:
        kwargs["dtype"] = args.dtype
    pilot = args.pilot if args.pilot is not None else options.get("pilot")
    known = bool(options.get("known_cells"))
    if known:  # what it needs, before any compute
        from .maps.labels import basins
        from .maps.refine import _check_known_cells

        if folder is not None:
            return _error("[run] known_cells = true cannot be used with --checkpoint or "
                          "--resume (the known cells are not kept in a checkpoint); "
                          "accepted: sweep run without them")
        _check_known_cells(True, scene, grid, basins, pilot, kwargs)
        from .maps.known import KNOWN_MIN_POINTS

        small = {d: len(v) for d, v in grid.axes.items() if len(v) < KNOWN_MIN_POINTS}
        if small:
            return _error(f"[run] known_cells = true needs {KNOWN_MIN_POINTS} points or "
                          f"more per axis (the settled cells of coarser maps hide finer "
                          f"structure: 1 % of the labels differed at 48); the [grid] has "
                          f"{', '.join(f'{d} {n}' for d, n in small.items())}; accepted: a "
                          "finer grid, or known_cells = false")
    if options.get("refine"):
        return _command_refine(args, scene, grid, kwargs, options, output, folder, pilot)
    if pilot is not None:
        from .maps.pilot import pilot_catalogue
        from .physics.system import System

        if isinstance(scene, System):  # a driven system's: as [run] pilot (--pilot N)
            from .toml_pilot import check_system_pilot

            check_system_pilot(scene, grid, pilot, kwargs)
        else:  # refuse a bad pilot before any compute
            from .toml_pilot import check_scene_pilot

            check_scene_pilot(scene, grid, pilot, kwargs)
    elif not args.no_space_check:  # with a pilot, after it: its catalogue adds variables
        check_space(output, scene, grid, **kwargs)
    client = _client(args, options)
    if args.resume and _no_checkpoint(folder):  # as wget -c: the same command starts it
        print(f"sweep: note: --resume: no checkpoint in {str(folder)!r}; the run starts "
              "from the beginning", file=sys.stderr)
    bar = "\n" if args.progress or (args.progress is None and sys.stderr.isatty()) else ""
    stop = _Stop(lambda word, what: f"{bar}sweep: {word} (the running chunk did not end "
                 f"within {TERMINATE_WAIT_S:g} s of {what} and was abandoned); "
                 f"{_resume_hint(args, folder, output)}")
    saving = False
    try:
        with stop:
            if pilot is not None:  # after the scheduler answered: no pilot for a dead one
                started = time.perf_counter()
                kwargs["attractors"] = pilot_catalogue(scene, grid, pilot, **kwargs)
                pilot_line = _pilot_summary(scene, grid, pilot, kwargs["attractors"],
                                            time.perf_counter() - started)
                if known:  # coarse maps of the grid, then stop on their settled cells
                    from .maps.known import background, fixed_axes

                    run = {k: v for k, v in kwargs.items() if k != "attractors"}
                    cells, _ = background(scene, grid.axes["theta0"], grid.axes["omega0"],
                                          kwargs["attractors"], fixed=fixed_axes(grid),
                                          **run)
                    if cells is not None:  # None: a grid too small for a background
                        kwargs["known_cells"] = cells
                if not args.no_space_check:
                    check_space(output, scene, grid, **kwargs)
            ds, seconds = _run_quietly(scene, grid, progress=args.progress, client=client,
                                       **kwargs)
            saving = True
            save(ds, output)
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (Terminated)
        word, status = _stopped(exc)
        stop.say(f"{bar}sweep: {word}; {_resume_hint(args, folder, output)}")
        return status
    except OSError as exc:  # a full disk: keep what the checkpoint holds, say how to use it
        if folder is None or not (folder / _checkpoint.MANIFEST).is_file():
            raise
        return _error(f"{exc}; {_resume_hint(args, folder, output, elsewhere=saving)}")
    finally:
        if client is not None:
            client.close()
    if folder is not None:
        _checkpoint.remove(folder)
    if pilot is not None:
        print(pilot_line)
    print(f"wrote {output}: {_summary(ds, grid, seconds)}")
    return 0


def _no_checkpoint(folder: Path) -> bool:
    """Whether ``--resume`` finds nothing at all to resume in ``folder``: it does not exist
    (its parent does) or it is an empty folder. Anything else is `sweep.run`'s to
    resume, or to refuse in one line (a file, other files, another run's checkpoint)."""
    if folder.is_dir():
        return not any(folder.iterdir())
    parent = folder.parent if str(folder.parent) else Path(".")
    return not folder.exists() and parent.is_dir()


def _netcdf_name(option: str, path: str) -> None:
    """Refuse an output file of netCDF whose name does not end in ``.nc`` (any case):
    ``-o x.csv`` would write netCDF under a name that says otherwise."""
    suffix = Path(path).suffix
    if suffix.lower() != ".nc":
        ends = f"ends in {suffix!r}" if suffix else "has no suffix"
        raise ValueError(f"{option} {str(path)!r}: the file is netCDF, and its name {ends}; "
                         "accepted: a file name ending in .nc")


def _command_refine(args, scene, grid, kwargs, options, output, folder, pilot) -> int:
    """``sweep run`` of a run file with ``[run] refine = true``: `sweep.maps.refine`
    of the grid with ``refine_label`` (default ``basins``) and ``refine_step``; writes
    the map's labels with their ``computed`` mask (not the trajectories' variables)."""
    from . import maps
    from .io import save
    from .maps.refine import refine
    from .toml_spec import REFINE_MAPS

    if folder is not None:
        return _error("--checkpoint and --resume do not apply to [run] refine = true (it "
                      "runs one sweep per level); accepted: sweep run without them")
    name = options.get("refine_label", "basins")
    label = getattr(maps, name) if name in REFINE_MAPS else name
    client = _client(args, options)
    if client is not None:
        kwargs["client"] = client
    if args.progress is not None:
        kwargs["progress"] = args.progress
    start = time.perf_counter()
    try:
        with _Stop(lambda word, what: f"sweep: {word}; no output written"), \
                _warnings_as_lines():
            labels = refine(scene, grid, label, step=options.get("refine_step", 16),
                            pilot=41 if pilot is None else pilot,
                            known_cells=bool(options.get("known_cells")), **kwargs)
    except KeyboardInterrupt as exc:
        word, status = _stopped(exc)
        print(f"sweep: {word}; no output written (a refined map is not resumable)",
              file=sys.stderr)
        return status
    finally:
        if client is not None:
            client.close()
    seconds = time.perf_counter() - start
    save(labels.to_dataset(), output)
    computed = labels.attrs["cells_computed"]
    print(f"wrote {output}: refined {labels.name} map ({_shape(grid)}), {computed} of "
          f"{grid.size} trajectories computed ({100 * computed / grid.size:.1f} %) in "
          f"{seconds:.2f} s wall time")
    return 0


class Terminated(KeyboardInterrupt):
    """SIGTERM stopped ``sweep run`` (raised once the running kernel's threads stop:
    `_Stop`).

    A KeyboardInterrupt, so that everything that cleans up after Ctrl-C (the checkpoint,
    its lock, a half-written output file) does so after SIGTERM too.
    """


#: signal number -> how `_Stop` says a stop it forced: (word, what the user did or the
#: process was sent, exit status)
_STOPS = {int(signal.SIGINT): ("interrupted", "Ctrl-C", EXIT_INTERRUPTED),
          int(signal.SIGTERM): ("terminated", "SIGTERM", EXIT_TERMINATED)}


class _Stop:
    """Ctrl-C (SIGINT) and SIGTERM stop ``sweep run`` within `TERMINATE_WAIT_S` seconds:
    in effect in a ``with`` block (main thread, POSIX; elsewhere it does nothing).

    Python runs a signal handler in the main thread between two bytecodes. While a
    chunk's kernel runs, the main thread waits for the kernel's threads
    (`sweep.kernels.threads.run_blocks`), so the handler runs at once; the raise is
    held back until the threads have ended the pieces of blocks they were computing
    (none starts another; a refill kernel's piece spans the chunk), as they write into
    the run's arrays. Ctrl-C raises KeyboardInterrupt (Python's own handler); SIGTERM
    raises `Terminated` (this block's handler), which unwinds the run exactly as Ctrl-C
    does: the chunks already stored stay in the checkpoint (the one that was running is
    dropped and recomputed on resume), the checkpoint's lock is released, a
    half-written output file is deleted, and ``sweep run`` prints the resume command
    and exits with `EXIT_INTERRUPTED` or `EXIT_TERMINATED`.

    A chunk lasts about a second by default (`sweep.engine.default_chunk_size`), but a
    large ``chunk_size`` can make one last minutes: past a batch system's grace period
    after SIGTERM (then SIGKILL: no message, a stale lock file), and past the patience
    of whoever pressed Ctrl-C. So a watchdog thread, woken by the signal itself
    (`signal.set_wakeup_fd`: the interpreter writes the signal's number to a pipe at
    once, whatever the main thread does; the kernels release the GIL, so the thread
    runs beside them), waits `TERMINATE_WAIT_S` seconds for the block to end. If it has
    not, the thread prints the line, releases the checkpoint locks
    (`sweep.execution.lock.release_all`), deletes a half-written output file
    (`sweep.io.discard_partial_files`) and ends the process with ``os._exit`` and the
    signal's exit status. The stored chunks are whole files at any moment (each is
    renamed into place complete).

    A signal the parent process ignores stays ignored (a ``sweep run &`` of a script
    inherits SIGINT ignored); Ctrl-C is watched only while SIGINT has Python's own
    handler. The previous SIGTERM handler and wakeup fd are restored when the block
    ends. A second signal changes nothing: the bound runs from the first.

    Parameters
    ----------
    line : callable
        ``line(word, what)`` -> the message of a stop forced by the watchdog, with
        ``word`` ``"interrupted"`` or ``"terminated"`` and ``what`` ``"Ctrl-C"`` or
        ``"SIGTERM"``.
    """

    def __init__(self, line) -> None:
        self._line = line
        self._said = False
        self._say_lock = threading.Lock()
        self._done = threading.Event()
        self._raised = False
        self._armed = False
        self._previous = None

    def __enter__(self) -> _Stop:
        if os.name != "posix" or threading.current_thread() is not threading.main_thread():
            return self
        watched = set()
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            watched.add(int(signal.SIGINT))
        term = signal.getsignal(signal.SIGTERM) != signal.SIG_IGN
        if term:
            watched.add(int(signal.SIGTERM))
        if not watched:
            return self
        self._watched = watched
        self._wait_s = float(TERMINATE_WAIT_S)
        self._read, self._write = os.pipe()
        os.set_blocking(self._write, False)  # set_wakeup_fd needs a non-blocking fd
        self._watchdog = threading.Thread(target=self._watch, name="sweep-stop",
                                          daemon=True)
        self._watchdog.start()
        self._previous_fd = signal.set_wakeup_fd(self._write, warn_on_full_buffer=False)
        self._armed = True
        self._term = term
        if term:
            self._previous = signal.signal(signal.SIGTERM, self._handle)
        return self

    def __exit__(self, *exc_info) -> bool:
        if self._armed:
            self._armed = False
            self._done.set()
            if self._term:
                signal.signal(signal.SIGTERM, self._previous if self._previous is not None
                              else signal.SIG_DFL)
            signal.set_wakeup_fd(self._previous_fd)
            os.close(self._write)  # the watchdog's read returns: it ends
            self._watchdog.join(timeout=1.0)
            os.close(self._read)
        return False

    def _handle(self, signum, frame) -> None:
        if not self._raised:  # the first SIGTERM stops the run; later ones change nothing
            self._raised = True
            raise Terminated

    def _watch(self) -> None:
        while True:
            try:
                data = os.read(self._read, 64)
            except OSError:
                return
            if not data:  # the block ended
                return
            caught = [number for number in data if number in self._watched]
            if caught:  # one byte per signal caught; the first one sets the exit
                if not self._done.wait(self._wait_s):
                    self._force(caught[0])
                return

    def _force(self, signum: int) -> None:
        """End the process now: the main thread did not stop in time."""
        word, what, status = _STOPS[signum]
        try:
            # never wait on a stuck main thread
            if self._say_lock.acquire(timeout=1.0) and not self._said:
                self._said = True
                try:
                    line = self._line(word, what)
                except Exception:  # noqa: BLE001 - the exit must not depend on it
                    line = f"sweep: {word}"
                os.write(2, (line + "\n").encode())
            from .execution import lock as _lock
            from .io import discard_partial_files

            _lock.release_all()
            discard_partial_files()
        finally:
            os._exit(status)

    def say(self, text: str) -> None:
        """Print ``text`` on stderr unless the watchdog has printed its line."""
        with self._say_lock:
            if not self._said:
                self._said = True
                print(text, file=sys.stderr, flush=True)


#: Seconds to wait for a Dask scheduler to answer before giving up.
CONNECT_TIMEOUT_S = 30


def _connect(address: str):
    """A `dask.distributed.Client` of the scheduler at ``address``.

    Raises
    ------
    ValueError
        One line: dask is not installed (how to install it), the address is not one,
        or the scheduler cannot be reached within `CONNECT_TIMEOUT_S`.
    """
    from .toml_spec import check_scheduler

    address = check_scheduler("--scheduler", address)
    try:
        from distributed import Client
    except ImportError:
        raise ValueError(f"--scheduler {address}: running on a Dask cluster needs "
                         "dask.distributed, which is not installed; accepted: pip install "
                         "'dask[distributed]' (the extra dask), or run without --scheduler "
                         "(and without [run] scheduler)") from None
    try:
        return Client(address, timeout=CONNECT_TIMEOUT_S)
    except Exception as exc:  # noqa: BLE001 - OSError, TimeoutError, ValueError (address)
        raise ValueError(f"cannot connect to the Dask scheduler at {address!r}: "
                         f"{' '.join(str(exc).split()) or type(exc).__name__}; accepted: the "
                         "address of a running scheduler (dask scheduler prints it)") \
            from None


def _resume_hint(args: argparse.Namespace, folder, output: Path, *,
                 elsewhere: bool = False) -> str:
    """The end of the one-line interruption message: how to resume (or why one cannot).

    ``elsewhere``: the output file could not be written; the command names the
    checkpoint folder, so that it works with another ``-o`` too.
    """
    import shlex

    from .execution.checkpoint import _CHUNK

    if folder is None:
        return ("no output written; run with --checkpoint DIR (or --resume) to make a run "
                "resumable")
    done = sum(1 for p in folder.iterdir() if _CHUNK.match(p.name)) if folder.is_dir() else 0
    command = ["sweep", "run", args.run_file, "-o", str(output)]
    if elsewhere or (args.checkpoint is not None
                     and Path(args.checkpoint) != default_checkpoint(output)):
        command += ["--checkpoint", str(folder)]
    if getattr(args, "scheduler", None) is not None:
        command += ["--scheduler", args.scheduler]
    if getattr(args, "pilot", None) is not None:  # the same catalogue, the same run
        command += ["--pilot", str(args.pilot)]
    command.append("--resume")
    where = (" (once there is room; another -o writes the file elsewhere, without "
             "recomputing)") if elsewhere else ""
    return (f"{done} finished chunks are checkpointed in {str(folder)!r}; resume with: "
            f"{shlex.join(command)}{where}")


# ------------------------------------------------------------------------------- demo
def demo_inputs(size: int):
    """Scene, grid and run keyword arguments of ``sweep demo`` for a size x size grid.

    Parameters
    ----------
    size : int
        Grid points per axis, >= 2.

    Returns
    -------
    scene : Scene
    grid : Grid
        ``theta0`` in [-pi, pi] rad x ``omega0`` in [-10, 10] rad/s.
    run_kwargs : dict
    """
    from .grid import Grid
    from .physics import Damping, Scene

    if isinstance(size, bool) or not isinstance(size, int) or size < 2:
        raise ValueError(f"--size must be an integer >= 2 (grid points per axis), "
                         f"got {size!r}")
    scene = Scene(gravity=DEMO["gravity"], length=DEMO["length"], model="nonlinear",
                  effects=(Damping(DEMO["damping"]),))
    grid = Grid(theta0=np.linspace(*DEMO["theta0"], size),
                omega0=np.linspace(*DEMO["omega0"], size))
    return scene, grid, {"t_end": DEMO["t_end"], "dt": DEMO["dt"],
                         "observe": DEMO["observe"]}


def _command_demo(args: argparse.Namespace) -> int:
    """``sweep demo``: run the demo sweep; write demo.nc and two PNG maps (well,
    capture time)."""
    from . import plot
    from .engine import _check_memory, prepare
    from .io import check_output_path, save

    scene, grid, kwargs = demo_inputs(args.size)
    folder = Path(args.output)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"output folder {str(folder)!r} exists and is not a folder; "
                         "accepted: a folder path (created if missing)")
    settings, spec, _ = prepare(scene, grid, **kwargs)  # before the folder is made
    try:
        _check_memory(grid.size, spec, settings)
    except ValueError as exc:
        raise ValueError(f"--size {args.size}: {exc}") from None
    created = _missing_folders(folder)
    folder.mkdir(parents=True, exist_ok=True)
    try:
        netcdf = check_output_path(folder / "demo.nc")
        ds, seconds = _run_quietly(scene, grid, progress=args.progress, **kwargs)
        save(ds, netcdf)
    except BaseException:  # an error, Ctrl-C: no empty folder left behind
        for made in created:  # deepest first; one that holds anything stays
            with contextlib.suppress(OSError):
                made.rmdir()
        raise
    written = [netcdf, *_demo_maps(ds, folder, plot)]
    print(f"demo: {_summary(ds, grid, seconds)}")
    for path in written:
        print(f"wrote {path}")
    return 0


def _missing_folders(folder: Path) -> list[Path]:
    """The folders ``folder.mkdir(parents=True)`` would create, deepest first."""
    missing = []
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    return missing


def _demo_maps(ds, folder: Path, plot) -> list[Path]:
    """The demo dataset's maps as PNG files in ``folder``: the well each start is
    captured in, and the time it takes (``capture``); the winding map would repeat the
    well map, since every start of the window lies in well 0."""
    _use_agg()
    setting = (f"damped pendulum, c = {DEMO['damping']:g} 1/s, "
               f"g/L = {DEMO['gravity'] / DEMO['length']:g} 1/s²")
    maps = {
        "well.png": (ds.well.assign_attrs(long_name="well k captured in (rest at θ = 2πk)"),
                     f"Well captured in ({setting})"),
        "capture_time.png": (ds.capture_time.assign_attrs(
                                 long_name="time until captured in a well"),
                             f"Time until capture ({setting})"),
    }
    written = []
    for name, (da, title) in maps.items():
        written.append(plot.save_figure(plot.map(da, title=title), folder / name))
    return written


# ------------------------------------------------------------------------------- plot
def _parse_selection(items: list[str]) -> dict[str, float]:
    """``["theta0=-120deg", "omega0=0"]`` -> ``{"theta0": -2.094..., "omega0": 0.0}``."""
    selection = {}
    for item in items:
        name, sep, text = item.partition("=")
        name, text = name.strip(), text.strip()
        degrees = text.lower().endswith("deg")
        number = text[:-3] if degrees else text
        try:
            value = float(number)
        except ValueError:
            value = None
        if not sep or not name or value is None or not math.isfinite(value):
            raise ValueError(f"--sel {item!r}: accepted: DIM=VALUE with a finite number "
                             "VALUE, optionally with a 'deg' suffix (theta0=-120deg)")
        if name in selection:
            raise ValueError(f"--sel {name} given twice; accepted: one value per dimension")
        selection[name] = math.radians(value) if degrees else value
    return selection


#: How far (a fraction of an axis's smallest spacing) a ``--sel`` value may lie from a
#: value of the axis. 1 %: far above the rounding of a value typed in degrees
#: (-120deg) or copied from a printout with 6 digits, far below the half spacing that
#: separates two values, so that a value accepted is one value of the axis, never one
#: between two (which the nearest one used to replace silently).
SELECTION_TOLERANCE = 0.01


#: How far (relative, absolute below 1) a ``--sel`` value may lie from the value of an
#: axis of one value: 1e-6, above the rounding of the 6 significant digits that the
#: refusal of another value prints (5e-7 relative at most), so that they select it.
SINGLE_VALUE_TOLERANCE = 1e-6


def _check_selection(ds, selection: dict[str, float], items: list[str]) -> None:
    """Refuse a ``--sel DIM=VALUE`` whose VALUE is not a value of the axis DIM of ``ds``
    (within `SELECTION_TOLERANCE` of its spacing; an axis of one value: within
    `SINGLE_VALUE_TOLERANCE` of it). Names that are not axes are left to
    `sweep.plot.select`, which names the axes."""
    texts = {item.partition("=")[0].strip(): item.strip() for item in items}
    for name, value in selection.items():
        if name not in ds.dims or name not in ds.coords or ds[name].ndim != 1 \
                or not np.issubdtype(ds[name].dtype, np.number):
            continue
        values = np.unique(np.asarray(ds[name].values, dtype=float))
        if values.size > 1:
            tolerance = SELECTION_TOLERANCE * float(np.diff(values).min())
        else:  # the 6 significant digits the refusal below prints select it
            tolerance = SINGLE_VALUE_TOLERANCE * max(1.0, abs(float(values[0])))
        if float(np.abs(values - value).min()) <= tolerance:
            continue
        units = ds[name].attrs.get("units", "")
        if values.size <= 12:
            accepted = f"one of {', '.join(f'{v:.6g}' for v in values)} {units}"
        else:
            accepted = (f"one of its {values.size} values from {values[0]:.6g} to "
                        f"{values[-1]:.6g} {units}")
        degrees = " (or in degrees, with a 'deg' suffix)" if units == "rad" else ""
        raise ValueError(f"--sel {texts.get(name, name)}: {value:.6g} is not a value of "
                         f"the axis {name}; accepted: {accepted.rstrip()}{degrees}")


def _command_fractions(args: argparse.Namespace) -> int:
    """``sweep fractions``: label a file's trajectories, print each label's fraction and
    standard error (`sweep.maps.fractions`), optionally write them as CSV."""
    from . import maps
    from .io import check_output_path
    from .maps.fractions import GRID, label_text
    from .maps.requirements import file_labels
    from .toml_spec import REFINE_MAPS

    output = check_output_path(args.output) if args.output is not None else None
    ds = _load(args.file)
    if args.label not in REFINE_MAPS and args.label not in ds.data_vars:
        raise ValueError(f"--label {args.label!r} is neither a map nor a variable of "
                         f"{args.file!r}; accepted: {', '.join(REFINE_MAPS)}, or one of "
                         f"{', '.join(map(str, ds.data_vars))}")
    try:
        labels = getattr(maps, args.label)(ds) if args.label in REFINE_MAPS \
            else ds[args.label]
        table = maps.fractions(labels)
    except ValueError as error:  # name the labels that work on this file
        working = file_labels(ds, args.label)
        hint = (f"; labels that work on {args.file!r}: "
                + ", ".join(f"--label {n}" for n in working)) if working else ""
        raise ValueError(f"--label {args.label}: {error}{hint}") from None
    if args.convergence:  # a grid's is refused: its first cells are not a sample
        try:
            table = maps.fractions(labels, convergence=True)
        except ValueError as error:
            why = str(error).removeprefix("convergence=True: ").split("; accepted:")[0]
            raise ValueError(f"--convergence: {why}; accepted: a file of a [sample] or "
                             "[points] run (sweep.sample), or no --convergence") from None
    frame = table.to_dataframe()
    frame.index = frame.index.set_levels(
        [label_text(v) for v in frame.index.levels[-1]], level=-1) \
        if frame.index.nlevels > 1 else [label_text(v) for v in frame.index]
    frame.index.names = table.fraction.dims
    method = table.attrs["standard_error_method"]
    errors = ("a grid: no standard errors, its cells are not a random sample"
              if method == GRID else method.split(":")[0])
    print(f"{args.file}: {int(table.attrs['samples'])} trajectories, {args.label} "
          f"({errors})")
    shown = frame.drop(columns="standard_error") if method == GRID else frame
    print(shown.to_string())  # a grid's column of NaN errors is not printed (the CSV has it)
    if output is not None:
        tmp = output.with_name(output.name + ".tmp")
        frame.to_csv(tmp)
        tmp.replace(output)  # never a half-written table
        print(f"wrote {output}")
    return 0


def parse_ladder(items: list[str]) -> dict:
    """``["dt=0.2,0.1", "dtype=float32,float64"]`` -> ``{"dt": [0.2, 0.1], "dtype":
    ["float32", "float64"]}`` (numbers for the numeric settings; `sweep.map_accuracy`
    checks the values)."""
    from .map_precision import LADDER_KEYS

    ladder = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        values = [v.strip() for v in text.split(",")]
        if not sep or key not in LADDER_KEYS or not all(values):
            raise ValueError(f"--ladder {item!r}: accepted: KEY=V1,V2,... with KEY one of "
                             f"{', '.join(LADDER_KEYS)} and its values least to most "
                             "accurate (dt=0.2,0.1,0.05)")
        if key in ladder:
            raise ValueError(f"--ladder {key} given twice; accepted: one ladder per setting")
        if key not in ("dtype", "method"):
            try:
                values = [float(v) for v in values]
            except ValueError:
                raise ValueError(f"--ladder {item!r}: {key} takes numbers; accepted: "
                                 f"{key}=V1,V2,... with finite numbers") from None
        ladder[key] = values
    return ladder


def _pendulum_only(command: str, run_file: str, scene) -> None:
    """Refuse a ``[system]`` run file in ``sweep COMMAND``, made for the single
    pendulum only (before anything runs)."""
    from .physics import Scene

    if not isinstance(scene, Scene):
        raise ValueError(f"sweep {command} supports single-pendulum run files only; "
                         f"{run_file!r} has a [system] table ({type(scene).__name__}); "
                         "accepted: a run file with a [scene] table, or with neither (the "
                         "default pendulum)")


def _command_map_accuracy(args: argparse.Namespace) -> int:
    """``sweep map-accuracy``: `sweep.map_accuracy` of a run file's starts under the
    ``--ladder`` settings; print the table, optionally write the netCDF and the figure
    (each atomically, after everything is computed)."""
    from . import maps
    from .io import check_output_path
    from .map_precision import map_accuracy
    from .toml_spec import REFINE_MAPS, load_run

    ladder = parse_ladder(args.ladder)
    if args.output is not None:
        _netcdf_name("-o", args.output)
    output = check_output_path(args.output) if args.output is not None else None
    figure = check_output_path(args.figure) if args.figure is not None else None
    if output is not None and figure is not None and output.resolve() == figure.resolve():
        raise ValueError(f"-o and --figure name the same file {str(output)!r}; accepted: "
                         "two different files")
    if figure is not None:
        _use_agg()
        from matplotlib.figure import Figure

        fmt = figure.suffix.lstrip(".").lower() or "png"
        supported = Figure().canvas.get_supported_filetypes()
        if fmt not in supported:
            raise ValueError(f"--figure {str(figure)!r}: unknown image format {fmt!r}; "
                             f"accepted: {', '.join(sorted(supported))}")
    options = {}
    scene, starts, kwargs = load_run(args.run_file, options)
    _pendulum_only("map-accuracy", args.run_file, scene)
    if options.get("scheduler") is not None:
        raise ValueError("sweep map-accuracy runs locally; [run] scheduler is not used "
                         "here; accepted: a run file without scheduler")
    label = getattr(maps, args.label) if args.label in REFINE_MAPS else args.label
    pilot = args.pilot if args.pilot is not None else options.get("pilot", 41)
    start = time.perf_counter()
    with _warnings_as_lines():
        accuracy = map_accuracy(scene, starts, label, ladder, repeats=args.repeats,
                                pilot=pilot, **kwargs)
    seconds = time.perf_counter() - start
    table = accuracy.table()
    sampled = bool(accuracy.dataset.attrs["sampled"])
    print(f"{args.run_file}: {args.label} of {starts.size} starts ({_shape(starts)}), "
          f"{'binomial standard errors' if sampled else 'a grid: no standard errors'}, "
          f"{seconds:.2f} s end to end")
    shown = table if sampled else table.drop(columns="differing_error", errors="ignore")
    print(shown.to_string(float_format=lambda v: f"{v:.4g}"))  # a grid's NaN: not printed
    for key in ladder:
        if key not in ("dtype", "method"):
            rate = accuracy.rate(key)
            print(f"rate of differing against {key}: " + (
                f"{rate:.3g} (log-log least-squares slope)" if math.isfinite(rate) else
                f"not computed (it needs two levels of {key} whose labels differ from the "
                "reference)"))
    if output is not None:
        accuracy.save(output)
        print(f"wrote {output}")
    if figure is not None:
        from . import plot

        plot.save_figure(plot.map_accuracy(accuracy), figure)
        print(f"wrote {figure}")
    return 0


def _command_boundary(args: argparse.Namespace) -> int:
    """``sweep boundary``: `sweep.maps.describe_boundary` of a run file's 2-D map;
    print it, optionally write it as JSON (atomically)."""
    import json

    from . import maps
    from .grid import Grid
    from .io import check_output_path
    from .maps.boundary import describe_boundary, label_grid
    from .maps.requirements import label_refusal
    from .toml_spec import REFINE_MAPS, load_run

    output = check_output_path(args.output) if args.output is not None else None
    if args.label not in REFINE_MAPS:
        raise ValueError(f"--label {args.label!r} is not a map; accepted: "
                         f"{', '.join(REFINE_MAPS)}")
    for name, value, low in (("--sampled", args.sampled, 0), ("--wada", args.wada, 0),
                             ("--seed", args.seed, 0), ("--pilot", args.pilot, 2)):
        if value is not None and value < low:
            raise ValueError(f"{name} must be >= {low}, got {value}")
    if 0 < args.sampled < 100:
        raise ValueError(f"--sampled must be 0 or >= 100 pairs per eps level, got "
                         f"{args.sampled}")
    options = {}
    scene, grid, kwargs = load_run(args.run_file, options)
    _pendulum_only("boundary", args.run_file, scene)
    varying = [d for d, values in getattr(grid, "axes", {}).items() if len(values) > 1]
    if not isinstance(grid, Grid) or sorted(varying) != ["omega0", "theta0"]:
        has = ("a [grid] varying " + ", ".join(varying)) if isinstance(grid, Grid) \
            else "no [grid]"
        raise ValueError(f"sweep boundary maps a [grid] of theta0 and omega0 (other axes "
                         f"one value); {args.run_file!r} has {has}")
    if options.get("scheduler") is not None:
        raise ValueError("sweep boundary runs locally; [run] scheduler is not used here; "
                         "accepted: a run file without scheduler")
    fixed = {d: float(values[0]) for d, values in grid.axes.items() if len(values) == 1}
    if fixed:
        raise ValueError(f"sweep boundary maps theta0 x omega0 of one scene; put "
                         f"{', '.join(fixed)} in [scene], not in [grid]")
    label = getattr(maps, args.label)
    observe = tuple(kwargs.get("observe") or ())
    has_forcing = scene.forcing is not None  # a Scene: _pendulum_only refused a system
    refusal = label_refusal(args.label, observe, has_forcing, repr(args.run_file),
                            stop_early=bool(kwargs.get("stop_early")))
    if refusal is not None:  # before anything runs, naming what would work
        raise ValueError(refusal)
    # a forcing, or a drive sampled stroboscopically (a pivot alone): a catalogue's basins
    forced = args.label == "basins" and (has_forcing or "strobe" in observe)
    if args.label == "basins" and not forced:  # the wells, numbered alike in every run
        label = maps.well
    if label is maps.well and "capture" not in observe \
            and not {"final", "energy"} <= set(observe):
        # the well is observed (capture, which stop_early allows) or read from the
        # final angle and energy
        kwargs["observe"] = observe + (("capture",) if kwargs.get("stop_early") else
                                       tuple(n for n in ("final", "energy")
                                             if n not in observe))
    start = time.perf_counter()
    with _warnings_as_lines():
        if forced:
            pilot = args.pilot if args.pilot is not None else options.get("pilot", 41)
            kwargs["attractors"] = maps.pilot_catalogue(scene, grid, pilot, **kwargs)
        labels_of = maps.scene_labels(scene, label, **kwargs)
        x, y = grid.axes["theta0"], grid.axes["omega0"]
        labels = label_grid(labels_of, x, y)
        report = describe_boundary(labels, x, y, labels_of, sampled=args.sampled,
                                   wada_steps=args.wada, seed=args.seed)
    seconds = time.perf_counter() - start
    what = "forced basins (pilot catalogue)" if forced else (
        "basins (wells)" if args.label == "basins" else args.label)
    print(f"{args.run_file}: {what}, {seconds:.2f} s end to end")
    for line in report.lines():
        print(line)
    if output is not None:
        tmp = output.with_name(output.name + ".tmp")
        tmp.write_text(json.dumps(report.to_dict(), indent=1), encoding="utf-8")
        tmp.replace(output)  # never a half-written file
        print(f"wrote {output}")
    return 0


def _command_plot(args: argparse.Namespace) -> int:
    """``sweep plot``: a 2-D map of ``--var``, a ``--trajectory`` figure or an
    ``--orbit-diagram``."""
    from . import plot
    from .io import check_output_path

    output = check_output_path(args.output)
    selection = _parse_selection(args.sel)
    ds = _load(args.file)
    _check_selection(ds, selection, args.sel)
    _use_agg()
    if args.trajectory:
        if "time" not in ds.dims:
            raise ValueError(f"--trajectory: {args.file} has no 'time' dimension (no sampled "
                             "trajectories); accepted: a file from a run with save_every "
                             "(in [run] of the run file)")
        fig = plot.trajectory(ds, **selection)
    elif args.orbit_diagram is not None:
        fig = plot.orbit_diagram(plot.select(ds, **selection) if selection else ds,
                                 along=args.orbit_diagram, degrees=not args.radians)
    else:
        if args.var not in ds.data_vars:
            raise ValueError(f"--var {args.var!r}: no such variable in {args.file}; "
                             f"accepted: {', '.join(map(str, ds.data_vars))}")
        da = plot.select(ds[args.var], **selection)
        fig = plot.map(da, degrees=not args.radians, cmap=args.cmap)
    plot.save_figure(fig, output)
    print(f"wrote {output}")
    return 0


def _load(path: str):
    """`sweep.load`, with errors that say which file could not be read."""
    from .io import load

    try:
        return load(path)
    except FileNotFoundError:
        raise
    except (OSError, ValueError) as exc:
        raise ValueError(f"cannot read {path!r} as a netCDF file written by sweep: "
                         f"{exc}") from None


def _command_explore(args: argparse.Namespace) -> int:
    """``sweep explore``: serve the browser explorer until Ctrl-C."""
    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port must be an integer from 0 to 65535 (0: a free port), "
                         f"got {args.port}")
    if args.run_file is None:
        scene, grid, kwargs = demo_inputs(400)
    else:
        from .toml_spec import load_run

        scene, grid, kwargs = load_run(args.run_file, {})
    if args.device is not None:
        kwargs["device"] = args.device
    try:
        from .explore import explore
        from .explore.app import main_serve
    except ImportError as exc:
        raise ValueError(str(exc)) from None
    with _warnings_as_lines():  # e.g. the map it opens on
        app = explore(scene, grid, **kwargs)
    return main_serve(app, port=args.port, host=args.host, open_browser=not args.no_browser)


def _use_agg() -> None:
    """Draw off-screen: the command line never opens a window."""
    import matplotlib

    matplotlib.use("Agg")
