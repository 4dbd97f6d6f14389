"""The paper's study as data (Paul, Licata & Mehta; DESIGN.md section 7)."""

from __future__ import annotations

from ..density import DensityModel, Exponential, Msis
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


#: Names of the three default models; the first is the reference (Cd_ref = 3.0912).
DEFAULT_MODELS = ("NRLMSIS 2.1", "NRLMSIS 2.0", "NRLMSISE-00")
REFERENCE_MODEL = DEFAULT_MODELS[0]


def case_space_weather(case: str, record: SpaceWeather | None = None) -> SpaceWeather:
    """The space-weather record of a case: observed for Cases I/II, geomagnetic indices at
    their 2000-2019 mean for the simulated Cases III/IV."""
    if case not in CASE_EPOCHS:
        raise ValueError(f"unknown case {case!r}; expected one of {list(CASE_EPOCHS)}")
    record = record if record is not None else SpaceWeather()
    return record.mean_geomagnetic() if case.endswith("-simulated") else record


def case_models(case: str, record: SpaceWeather | None = None) -> dict[str, DensityModel]:
    """The paper's three stand-in models for a case: NRLMSIS 2.1 (reference), NRLMSIS 2.0
    and NRLMSISE-00, all with the default driver uncertainty. Note: NRLMSIS 2.0 and 2.1
    give identical mass densities (2.1 changed only nitric oxide), so they are the same
    component twice; see docs/conventions.md."""
    sw = case_space_weather(case, record)
    return {
        "NRLMSIS 2.1": Msis("2.1", space_weather=sw),
        "NRLMSIS 2.0": Msis("2.0", space_weather=sw),
        "NRLMSISE-00": Msis("00", space_weather=sw),
    }


#: Labels of the paper's five kappa processes (the keys of ``studies.METHODS``).
LABELS = {
    "white_10s": "White 10 s",
    "interpolated_18min": "Interpolated 18 min",
    "interpolated_180min": "Interpolated 180 min",
    "gauss_markov_18min": "Gauss-Markov 18 min",
    "gauss_markov_180min": "Gauss-Markov 180 min",
}
