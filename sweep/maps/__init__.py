"""Maps of what each region of phase space does: pure functions ``Dataset -> DataArray``
that read a run's stored features (they never re-run the integrator), periodicity maps,
attractor continuation along a grid axis, basin metrics, frequency responses by
continuation, adaptive refinement of a 2-D map toward its boundaries (`refine`), the
uncertainty exponent from random pairs of starts (`uncertainty_sampled`), and the Wada
test of a map of three or more basins (`wada`, `wada_merging`).

``sweep.maps.metrics`` and ``sweep.maps.response`` are also reachable as
``sweep.metrics`` and ``sweep.response``.
"""

from .boundary import BoundaryReport, describe_boundary
from .continuation import continuation
from .fractions import fractions
from .labels import (
                     UNRESOLVED,
                     amplitude,
                     attractor_catalogue,
                     basins,
                     identify_attractors,
                     inverted,
                     motion,
                     natural_frequency_squared,
                     well,
)
from .networks import basin_stability, synchronized
from .period import NO_PERIOD, period
from .pilot import pilot_catalogue, pilot_grid
from .refine import refine
from .uncertainty import NAN_LABEL, SampledUncertainty, scene_labels, uncertainty_sampled
from .wada import Wada, WadaMerging, wada, wada_merging

__all__ = ["NAN_LABEL", "NO_PERIOD", "UNRESOLVED", "BoundaryReport", "SampledUncertainty", "Wada",
           "WadaMerging", "amplitude", "attractor_catalogue", "basin_stability", "basins",
           "continuation",
           "describe_boundary", "fractions", "identify_attractors", "inverted", "motion",
           "natural_frequency_squared", "period", "pilot_catalogue", "pilot_grid", "refine",
           "scene_labels", "synchronized", "uncertainty_sampled", "wada", "wada_merging",
           "well"]
