"""Density-uncertainty settings calibrated on observed orbit-averaged densities of CHAMP
(22 storm windows, 2001-2005) and GRACE-FO (12, 2019-2022) (docs/density-calibration.md).
They are the library's defaults; ``python benches/density_calibration.py`` recomputes them
from the data (a test checks that it does). Each model's ``preset="paper"`` keeps the
literature settings the paper study runs with."""

from __future__ import annotations

from typing import Literal

#: A model's settings: ``"calibrated"`` (the default) or ``"paper"`` (the literature values
#: the paper study runs with: no mean correction, the old sigmas).
Preset = Literal["calibrated", "paper"]
PRESETS: tuple[Preset, ...] = ("calibrated", "paper")

#: NRLMSIS 2.1 (and 2.0, equal in mass density): DriverUncertainty's model floor and
#: ap_relative (f107_relative 0.02 and ap_scale 1 kept).
MSIS_MODEL_FLOOR = 0.114
MSIS_AP_RELATIVE = 0.592
#: NRLMSIS 2.1: scale and F10.7 exponent of the mean correction.
MSIS_SCALE = 0.854
MSIS_F107_EXPONENT = -0.184

#: JB2008: ActivitySigma (quiet, storm, full_at in dTc K, ap_weight in K per ap unit)
#: and mean correction.
JB2008_QUIET, JB2008_STORM, JB2008_FULL_AT = 0.174, 0.293, 322.0
JB2008_AP_WEIGHT = 5.0
JB2008_SCALE = 0.892
JB2008_F107_EXPONENT = -0.319

#: Jacchia-Roberts 1971: ActivitySigma (quiet, storm, full_at in Kp) and mean correction.
JR_QUIET, JR_STORM, JR_FULL_AT = 0.190, 0.266, 6.70
JR_SCALE = 0.728
JR_F107_EXPONENT = -2.17

#: Kappa: two Gauss-Markov terms (:class:`rhoprop.kappa.TwoScale`), half-lives in s and
#: the slow term's share of the variance.
KAPPA_HALF_LIFE = 16_700.0
KAPPA_SLOW_HALF_LIFE = 378_000.0
KAPPA_SLOW_FRACTION = 0.537

#: Mixture weights of the three families by log score (:func:`rhoprop.ensemble`'s
#: default when its models are these families).
ENSEMBLE_WEIGHTS = {"NRLMSIS 2.1": 0.849, "JB2008": 0.151, "Jacchia-Roberts": 0.0}
#: The factor on every family's sigma inside that mixture, by log score at those weights
#: (a pool of calibrated families is over-dispersed where their means differ: the
#: spread-adjusted linear pool; :func:`rhoprop.ensemble`'s default with the weights).
ENSEMBLE_SPREAD = 0.861


def preset_argument(preset: object) -> Preset:
    """``preset`` checked: one of :data:`PRESETS` (ValueError naming them otherwise)."""
    if preset not in PRESETS:
        raise ValueError(f"preset must be one of {', '.join(PRESETS)}, got {preset!r}")
    return preset


#: The settings a calibration produces, by name (:func:`values`).
NAMES = (
    "MSIS_MODEL_FLOOR",
    "MSIS_AP_RELATIVE",
    "MSIS_SCALE",
    "MSIS_F107_EXPONENT",
    "JB2008_QUIET",
    "JB2008_STORM",
    "JB2008_FULL_AT",
    "JB2008_AP_WEIGHT",
    "JB2008_SCALE",
    "JB2008_F107_EXPONENT",
    "JR_QUIET",
    "JR_STORM",
    "JR_FULL_AT",
    "JR_SCALE",
    "JR_F107_EXPONENT",
    "KAPPA_HALF_LIFE",
    "KAPPA_SLOW_HALF_LIFE",
    "KAPPA_SLOW_FRACTION",
    "ENSEMBLE_SPREAD",
)


def values() -> dict[str, float]:
    """The stored settings by name: :data:`NAMES`, then ``"WEIGHT <family>"`` per family."""
    out = {name: float(globals()[name]) for name in NAMES}
    out.update({f"WEIGHT {k}": float(v) for k, v in ENSEMBLE_WEIGHTS.items()})
    return out
