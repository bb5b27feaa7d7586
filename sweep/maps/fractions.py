"""Basin stability: the fraction of sampled starts that each label takes, with its
standard error (Menck et al., Nature Physics 9, 89, 2013), from the labels of a run of
`sweep.sample` points (or of any run: every trajectory counts once)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import check_flag

__all__ = ["fractions", "label_text"]

#: The dimension `fractions` reads as independent replicates (R runs of
#: ``sweep.sample(..., seed=s)`` with R seeds, stacked along it).
REPLICATE = "replicate"

#: Smallest prefix of the convergence table (smaller ones say little).
FIRST_PREFIX = 16

BINOMIAL = ("binomial sqrt(p (1 - p) / n): exact for independent uniform samples "
            "(sample(method='random')); for scrambled Sobol points the error random "
            "sampling would have, conservative in practice (a basin indicator is "
            "discontinuous, so scrambling gains less than on smooth integrands, but it "
            "gains); an unbiased estimate: R independent seeds along a 'replicate' "
            "dimension")
GRID = ("none: the labels are a grid's cells, not a random sample (a grid's error is "
        "that of its resolution, not binomial; for one, sample the box: sweep.sample)")
SPREAD = ("spread of R independent replicates (randomised QMC): sample standard "
          "deviation of the R fractions / sqrt(R)")


def label_text(value) -> str:
    """A label as printed: whole numbers as integers (``1``, not ``1.0``), NaN as
    ``nan``, any other number as Python writes it."""
    number = float(value)
    if np.isnan(number):
        return "nan"
    return str(int(number)) if number == int(number) else repr(number)


#: The end of the long_name of a catalogued run's variable ``attractor`` (`sweep.run`
#: with ``attractors=``): -1, no attractor, is its 'no label'.
ATTRACTOR_NONE = "(-1: none)"


def _unresolved_code(labels, unresolved):
    """The label value that means 'no label', from the argument or the labels' own
    attributes (``unresolved`` of `sweep.maps.basins`, ``no_period`` of
    `sweep.maps.period`, the ``unresolved`` flag of `sweep.maps.motion`, -1 of a run's
    ``attractor`` variable, `ATTRACTOR_NONE`); None when there is none."""
    if unresolved is not None:
        return unresolved
    attrs = getattr(labels, "attrs", {})
    for key in ("unresolved", "no_period"):
        if key in attrs:
            return attrs[key]
    meanings = str(attrs.get("flag_meanings", "")).split()
    if "unresolved" in meanings and "flag_values" in attrs:
        return np.asarray(attrs["flag_values"])[meanings.index("unresolved")]
    if getattr(labels, "name", None) == "attractor" \
            and str(attrs.get("long_name", "")).endswith(ATTRACTOR_NONE):
        return -1  # a catalogued run's variable, its 'none' in its long_name
    return None


def _sampled(labels, sampled) -> bool:
    """Whether ``labels`` are a random sample: ``sampled`` if given, else False for a
    DataArray on grid dimensions (any but ``point`` and ``replicate``), True otherwise
    (`sweep.Points` runs, plain arrays)."""
    if sampled is not None:
        return check_flag("sampled", sampled)
    if isinstance(labels, xr.DataArray):
        return set(labels.dims) - {REPLICATE} <= {"point"}
    return True


def _check_whole(values: np.ndarray, labels) -> np.ndarray:
    """Float labels that are whole numbers (or NaN, no label), as int64 when none is
    NaN; refuses any other float, naming the variable."""
    if values.dtype.kind != "f":
        return values
    finite = values[np.isfinite(values)]
    bad = finite != np.round(finite)
    if bad.any() or np.isinf(values).any():
        name = getattr(labels, "name", None)
        what = f"variable {str(name)!r}" if name else "labels"
        value = float(finite[bad][0]) if bad.any() else float(values[np.isinf(values)][0])
        raise ValueError(f"{what} holds {value!r}, which is not a label; accepted: whole "
                         "numbers, one per trajectory (NaN: no label), such as a map of "
                         "sweep.maps (basins, motion, well, period) or an integer variable")
    if finite.size == values.size:
        return values.astype(np.int64)
    return values


def _table(values: np.ndarray) -> tuple[np.ndarray, bool]:
    """The labels present (sorted; NaN, if any, last) and whether NaN is one."""
    nan = values.dtype.kind == "f" and bool(np.isnan(values).any())
    present = np.unique(values[~np.isnan(values)] if nan else values)
    return (np.append(present.astype(np.float64), np.nan) if nan else present), nan


def _counts(values: np.ndarray, codes: np.ndarray, nan: bool) -> np.ndarray:
    """Per row of ``values`` (shape (R, n)), the count of each code, shape (R, k)."""
    known = codes[:-1] if nan else codes
    counts = (values[..., None] == known).sum(axis=-2)
    if nan:
        counts = np.concatenate([counts, np.isnan(values).sum(axis=-1)[:, None]], axis=-1)
    return counts


def _estimate(values: np.ndarray, codes, nan: bool):
    """Fraction, standard error and count per code of ``values``, shape (R, n)."""
    r, n = values.shape
    counts = _counts(values, codes, nan)
    p = counts / n
    if r == 1:
        return p[0], np.sqrt(p[0] * (1 - p[0]) / n), counts[0]
    return p.mean(axis=0), p.std(axis=0, ddof=1) / np.sqrt(r), counts.sum(axis=0)


def fractions(labels, *, convergence: bool = False, unresolved=None,
              sampled: bool | None = None) -> xr.Dataset:
    """The fraction of the samples each label takes, with its standard error.

    Parameters
    ----------
    labels : xarray.DataArray or array_like
        Per trajectory, a label (`sweep.maps.basins`, `motion`, `period`, `well`, ...),
        any shape: every trajectory counts once, in C order (for `sweep.Points`, the
        order of the points, so a Sobol sample's prefixes are its first points). A
        dimension named ``replicate`` (a DataArray's) holds R >= 2 independent samples,
        e.g. ``xr.concat([maps.basins(run(sample(n, seed=s))) ...], "replicate")``:
        the fraction is then their mean and its standard error their spread.
    convergence : bool, default False
        Also give the estimates over the first n samples for n = 16, 32, 64, ... (powers
        of two, where a Sobol sample is balanced) and the total: a dimension ``n``.
        Refused for a grid's labels (``sampled`` False): its first cells are a strip of
        the grid, not a sample.
    unresolved : scalar, optional
        The label that means 'no label' (a failed, chaotic or unmatched trajectory).
        Default: the labels' own ``unresolved`` attribute (`basins`: -1) or
        ``unresolved`` flag (`motion`: -127), -1 for a catalogued run's variable
        ``attractor``; NaN (`well`) is always no label. It is not
        dropped: it keeps a row of its own, flagged by the coordinate ``unresolved``, so
        the fractions of all rows sum to 1 and the resolved ones can be renormalised
        (divide by ``1 - fraction`` of the unresolved row) if that is what is wanted.
    sampled : bool, optional
        Whether the labels are a random sample of starts, which the binomial standard
        error assumes. Default: False for a DataArray on grid dimensions (a run of a
        `sweep.Grid`: its cells are not a random sample, and ``standard_error`` is NaN),
        True for one along ``point`` (`sweep.sample`, `sweep.Points`) and for a plain
        array. Replicates (``replicate``) always give their spread.

    Returns
    -------
    xarray.Dataset
        Dimension ``label`` (each label present, sorted; NaN last; int64 for whole
        float labels without NaN, e.g. ``attractor``), and ``n`` with
        ``convergence``. Variables ``fraction`` (count / n, or the replicates' mean),
        ``standard_error`` (one standard deviation of the fraction: ``sqrt(p (1 - p) /
        n)`` for one sample, the binomial error, exact for independent random samples;
        NaN for a grid; std over replicates / sqrt(R) with a ``replicate`` dimension)
        and ``count``
        (over all replicates); coordinate ``unresolved`` (bool per label); attributes
        ``samples`` (n per replicate), ``replicates`` and ``standard_error_method``.

    Raises
    ------
    ValueError
        For no labels, a single replicate, labels that are not numbers or not whole
        numbers (a float such as 0.37 is no label: ``amplitude``, ``energy_final``), or
        ``convergence`` of a grid's labels.

    Notes
    -----
    For scrambled Sobol samples (`sweep.sample`'s default) the binomial error is the
    error random sampling would have. Scrambled Sobol is unbiased and its variance is
    below random sampling's for smooth integrands; a basin indicator is discontinuous
    along a (here fractal) boundary, where the gain is smaller but not nil, so the
    binomial error is conservative in practice, though not a proven bound. Measured on
    the forced Wada map (examples/basin_stability.py): 8 independent scramblings of
    2048 points gave a spread 0.5-0.8 times the binomial error of their 16,384 points.
    For an estimate that needs no such argument, run R independent seeds and pass them
    along ``replicate``: the spread of the R fractions is an unbiased estimate of the
    variance (randomised quasi-Monte Carlo), itself uncertain by about 1 / sqrt(2 (R -
    1)) relative (27 % for R = 8).

    Examples
    --------
    >>> import numpy as np
    >>> from sweep import maps
    >>> table = maps.fractions(np.array([0, 0, 1, 1, 1, -1]), unresolved=-1)
    >>> table.fraction.values.round(3).tolist(), table.unresolved.values.tolist()
    ([0.167, 0.333, 0.5], [True, False, False])
    """
    convergence = check_flag("convergence", convergence)
    sampled = _sampled(labels, sampled)
    replicated = isinstance(labels, xr.DataArray) and REPLICATE in labels.dims
    if convergence and not sampled and not replicated:
        raise ValueError("convergence=True: the labels are a grid's cells, and its first "
                         "16, 32, ... cells (C order) are rows of its first axis, not a "
                         "sample of the box; accepted: the labels of sampled points "
                         "(sweep.sample), or sampled=True for labels that are a sample")
    code = _unresolved_code(labels, unresolved)
    if replicated:
        other = [d for d in labels.dims if d != REPLICATE]
        values = labels.transpose(REPLICATE, *other).values
        values = values.reshape(values.shape[0], -1)
        if values.shape[0] < 2:
            raise ValueError(f"labels have {values.shape[0]} replicate; accepted: R >= 2 "
                             "independent samples along 'replicate' (or no such dimension)")
    else:
        values = np.asarray(labels.values if isinstance(labels, xr.DataArray) else labels)
        values = values.reshape(1, -1)
    if values.dtype.kind not in "biuf":
        raise ValueError(f"labels must be numbers (int or float labels), got dtype "
                         f"{values.dtype}")
    if values.shape[1] == 0:
        raise ValueError("labels are empty; accepted: at least one labelled sample")
    values = _check_whole(values, labels)
    codes, nan = _table(values)
    flagged = np.isnan(codes) if codes.dtype.kind == "f" else np.zeros(codes.size, bool)
    if code is not None:
        flagged |= codes == code
    n = values.shape[1]
    prefixes = [n]
    if convergence:
        prefixes = [1 << k for k in range(FIRST_PREFIX.bit_length() - 1, n.bit_length())
                    if 1 << k < n] + [n]
    estimates = [_estimate(values[:, :m], codes, nan) for m in prefixes]
    p, se, counts = (np.array(column) for column in zip(*estimates))
    r = values.shape[0]
    if r == 1 and not sampled:
        se = np.full(se.shape, np.nan)
    dims = ("n", "label") if convergence else ("label",)
    if not convergence:
        p, se, counts = p[0], se[0], counts[0]
    ds = xr.Dataset(
        {"fraction": (dims, p, {"long_name": "fraction of the samples", "units": "1"}),
         "standard_error": (dims, se, {"long_name": "standard error of the fraction "
                                                    "(one standard deviation)", "units": "1"}),
         "count": (dims, counts, {"long_name": "samples with the label (all replicates)",
                                  "units": "1"})},
        coords={"label": ("label", codes, {"long_name": "label"}),
                "unresolved": ("label", flagged, {"long_name": "the label means no label "
                                                               "(failed, chaotic, unmatched)"})},
        attrs={"samples": n, "replicates": r,
               "standard_error_method": SPREAD if r > 1 else BINOMIAL if sampled else GRID})
    if convergence:
        ds = ds.assign_coords(n=("n", np.array(prefixes, dtype=np.int64),
                                 {"long_name": "samples used (the first n)"}))
    if isinstance(labels, xr.DataArray) and labels.name:
        ds.attrs["labels"] = str(labels.name)
    return ds
