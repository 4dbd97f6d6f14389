"""The paper's study as data (Paul, Licata & Mehta; docs/paper-study.md)."""

from __future__ import annotations

from ..density import DensityModel, Exponential, JacchiaRoberts, Jb2008, Jb2008Indices, Msis
from ..density.calibrated import Preset
from ..propagation import OrbitState, Spacecraft
from ..spaceweather import SpaceWeather
from ..time import EpochLike

#: Initial inertial position, m, and velocity, m/s.
PAPER_POSITION = (3782900.7032, -5441600.6779, -1420075.1327)
PAPER_VELOCITY = (-606.6600, 1539.2559, -7488.3946)
#: Reference drag coefficient and area-to-mass ratio (m^2/kg) of the paper's sphere.
PAPER_CD = 3.0912
PAPER_AREA_TO_MASS = 0.0015
#: Propagation span: 3 days, s.
PAPER_DURATION = 259200.0
#: Epochs of the four cases (III/IV share I/II's with mean geomagnetic drivers).
CASE_EPOCHS = {
    "solar-max-storm": "2002-09-07T01:00:00",
    "solar-min": "2009-12-02T00:00:00",
    "solar-max-simulated": "2002-09-07T01:00:00",
    "solar-min-simulated": "2009-12-02T00:00:00",
}


def paper_state(epoch: EpochLike = CASE_EPOCHS["solar-max-storm"]) -> OrbitState:
    """The paper's initial state at ``epoch`` (Case I by default)."""
    return OrbitState(epoch, PAPER_POSITION, PAPER_VELOCITY)


def paper_spacecraft(cd: float = PAPER_CD) -> Spacecraft:
    """The paper's sphere: Cd (default 3.0912) and A/m = 0.0015 m^2/kg."""
    return Spacecraft(cd, PAPER_AREA_TO_MASS)


def benchmark_exponential(rel_sigma: float = 0.0) -> Exponential:
    """The analytic benchmark atmosphere: rho = 3.725e-12 kg/m^3 at 400 km, H = 58.515 km."""
    return Exponential.benchmark(rel_sigma)


#: The default families: NRLMSIS 2.1 (reference, Cd_ref = 3.0912), JB2008 and
#: Jacchia-Roberts 1971; without JB2008 index files NRLMSISE-00 takes JB2008's place.
DEFAULT_MODELS = ("NRLMSIS 2.1", "JB2008", "Jacchia-Roberts 1971")
FALLBACK_MODELS = ("NRLMSIS 2.1", "Jacchia-Roberts 1971", "NRLMSISE-00")
REFERENCE_MODEL = DEFAULT_MODELS[0]
#: Years over which the simulated cases average the geomagnetic drivers (ap/Kp from the
#: CelesTrak record, dTc from the JB2008 file, clipped to the files' span).
MEAN_YEARS = ("2000-01-01", "2019-12-31")


def model_choice() -> tuple[tuple[str, ...], str, Jb2008Indices | None]:
    """(model names, why these, JB2008 indices or None): the three families when JB2008
    index files are found ($RHOPROP_JB2008_DATA, then the user cache), else the offline
    fallback, with the reason in words."""
    try:
        indices = Jb2008Indices.locate()
    except (OSError, ValueError) as error:
        return FALLBACK_MODELS, f"JB2008 index files unusable ({error}); " + _FALLBACK, None
    if indices is None:
        return (
            FALLBACK_MODELS,
            "JB2008 index files not found ($RHOPROP_JB2008_DATA unset and none in the user "
            "cache; see rp.density.Jb2008Indices.refresh); " + _FALLBACK,
            None,
        )
    first, last = indices.span
    return (
        DEFAULT_MODELS,
        "three model families: NRLMSIS 2.1 (reference, stand-in for MSIS-UQ), JB2008 "
        f"(stand-in for HASDM-ML; indices {indices.solfsmy.parent}, {first} to {last}) and "
        "Jacchia-Roberts 1971",
        indices,
    )


def case_space_weather(case: str, record: SpaceWeather | None = None) -> SpaceWeather:
    """The space-weather record of a case: observed for Cases I/II, geomagnetic indices at
    their 2000-2019 mean for the simulated Cases III/IV."""
    if case not in CASE_EPOCHS:
        raise ValueError(f"unknown case {case!r}; expected one of {list(CASE_EPOCHS)}")
    record = record if record is not None else SpaceWeather()
    return record.mean_geomagnetic() if case.endswith("-simulated") else record


_FALLBACK = (
    "running NRLMSIS 2.1 (reference), Jacchia-Roberts 1971 and NRLMSISE-00 (NRLMSISE-00 is "
    "the NRLMSIS family again, so only two families are distinct)"
)


def case_models(
    case: str, record: SpaceWeather | None = None, *, preset: Preset = "calibrated"
) -> dict[str, DensityModel]:
    """The paper's three stand-in models for a case, reference first (see
    :func:`model_choice` and :func:`default_models`). The simulated cases hold each
    family's geomagnetic driver at its long-term mean (ap/Kp over 2000-2019 from the
    record; dTc over the JB2008 file's years within 2000-2019). ``preset`` is the models'
    (the paper study passes ``"paper"``)."""
    return default_models(
        case_space_weather(case, record), mean_dtc=case.endswith("-simulated"), preset=preset
    )


def default_models(
    record: SpaceWeather | None = None,
    *,
    mean_dtc: bool = False,
    preset: Preset = "calibrated",
    as_of: EpochLike | None = None,
) -> dict[str, DensityModel]:
    """The default model families on ``record``, reference first: NRLMSIS 2.1 (driver
    uncertainty), JB2008 and Jacchia-Roberts 1971 (activity-dependent uncertainty) when
    JB2008 index files are available, else NRLMSIS 2.1, Jacchia-Roberts 1971 and
    NRLMSISE-00. ``mean_dtc`` holds JB2008's dTc at its 2000-2019 mean. NRLMSIS 2.0 (equal
    to 2.1 in mass density) is out of the default; use ``Msis("2.0")`` explicitly.
    ``preset``: the models' settings (:data:`rhoprop.density.PRESETS`). ``as_of`` (UTC):
    every model's drivers as a forecaster had them then (``record.as_of(as_of)`` and
    JB2008's ``indices.as_of(as_of)``: observed before it, the library's forecast
    after)."""
    sw = record if record is not None else SpaceWeather()
    names, _, indices = model_choice()
    if as_of is not None:
        sw = sw.as_of(as_of)
        indices = None if indices is None else indices.as_of(as_of)
    models: dict[str, DensityModel] = {"NRLMSIS 2.1": Msis("2.1", space_weather=sw, preset=preset)}
    for name in names[1:]:
        if name == "JB2008" and indices is not None:
            dtc = indices.mean_dtc(*MEAN_YEARS) if mean_dtc else None
            models[name] = Jb2008(indices, dtc=dtc, preset=preset, space_weather=sw)
        elif name == "Jacchia-Roberts 1971":
            models[name] = JacchiaRoberts(sw, preset=preset)
        elif name == "NRLMSISE-00":
            models[name] = Msis("00", space_weather=sw, preset=preset)
    return models


#: Labels of the paper's five kappa processes (the keys of ``studies.METHODS``).
LABELS = {
    "white_10s": "White 10 s",
    "interpolated_18min": "Interpolated 18 min",
    "interpolated_180min": "Interpolated 180 min",
    "gauss_markov_18min": "Gauss-Markov 18 min",
    "gauss_markov_180min": "Gauss-Markov 180 min",
}
