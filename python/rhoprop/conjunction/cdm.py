"""CCSDS Conjunction Data Messages (CCSDS 508.0-B-1), KVN or XML, read and written through
the maintained ``ccsds-ndm`` library (optional: ``pip install ccsds-ndm``, or the ``cdm``
extra of a checkout; it is GPL-3.0 licensed, so rhoprop never imports it unless a CDM is
read or written).

A :class:`ConjunctionMessage` holds what a Pc needs, in SI units: both objects' inertial
states at TCA (m, m/s), their covariances in their own RTN frames (m^2, m^2/s, m^2/s^2,
order R, T, N, Rdot, Tdot, Ndot), the drag parameter Cd*A/m when the message gives one,
and the hard-body radius when a ``COMMENT HBR = ...`` line gives one.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..io.files import sanitise
from ..options import HardBodyShape, NpdPolicy
from ..time import to_datetime64

if TYPE_CHECKING:
    from .probability import PcResult

#: Inertial reference frames a CDM may use for its states (all treated as one inertial
#: frame: their differences are far below a Pc's sensitivity).
INERTIAL_FRAMES = ("EME2000", "GCRF", "ICRF")

#: The 21 CDM covariance keywords, row-wise lower triangle of the 6x6 in the order
#: R, T, N, Rdot, Tdot, Ndot (CCSDS 508.0-B-1 section 3.5.2).
_COV_KEYS = (
    ("cr_r",),
    ("ct_r", "ct_t"),
    ("cn_r", "cn_t", "cn_n"),
    ("crdot_r", "crdot_t", "crdot_n", "crdot_rdot"),
    ("ctdot_r", "ctdot_t", "ctdot_n", "ctdot_rdot", "ctdot_tdot"),
    ("cndot_r", "cndot_t", "cndot_n", "cndot_rdot", "cndot_tdot", "cndot_ndot"),
)
_HBR = re.compile(r"\bHBR\s*=\s*([-+0-9.eE]+)\s*(?:\[?\s*(m|km)\s*\]?)?", re.IGNORECASE)


def _library() -> tuple[Any, Any, Any]:
    """The ``ccsds_ndm`` reader/writer, its formats and CDM model classes."""
    try:
        from ccsds_ndm.mapping import NDMFileFormats
        from ccsds_ndm.models import ndmxml4
        from ccsds_ndm.ndm_io import NdmIo
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError(
            "reading and writing CDMs needs the ccsds-ndm package: pip install ccsds-ndm"
        ) from err
    return NdmIo(), NDMFileFormats, ndmxml4


@dataclass(frozen=True)
class CdmObject:
    """One object of a conjunction data message.

    Attributes:
        name, designator: OBJECT_NAME and OBJECT_DESIGNATOR (catalog number).
        position: inertial position at TCA (3,), m.
        velocity: inertial velocity at TCA (3,), m/s.
        covariance: 6x6 state covariance in the object's own RTN frame (R = r/|r|,
            N = r x v/|r x v|, T = N x R), m^2, m^2/s, m^2/s^2.
        ref_frame: the message's REF_FRAME (one of :data:`INERTIAL_FRAMES`).
        drag_parameter: CD_AREA_OVER_MASS, m^2/kg, when given.
        international_designator: INTERNATIONAL_DESIGNATOR ("" when absent).
    """

    name: str
    designator: str
    position: np.ndarray
    velocity: np.ndarray
    covariance: np.ndarray = field(repr=False)
    ref_frame: str = "EME2000"
    drag_parameter: float | None = None
    international_designator: str = ""

    def __post_init__(self) -> None:
        for attr, shape in (("position", (3,)), ("velocity", (3,)), ("covariance", (6, 6))):
            value = np.array(getattr(self, attr), dtype=float)
            if value.shape != shape or not np.isfinite(value).all():
                raise ValueError(f"CdmObject {self.name!r}: {attr} must be {shape} finite")
            value.setflags(write=False)
            object.__setattr__(self, attr, value)
        if self.ref_frame not in INERTIAL_FRAMES:
            raise ValueError(
                f"CdmObject {self.name!r}: REF_FRAME {self.ref_frame!r} is not supported; "
                f"expected one of {INERTIAL_FRAMES}"
            )


@dataclass(frozen=True)
class ConjunctionMessage:
    """A conjunction data message, SI units.

    Attributes:
        tca: time of closest approach, UTC ``datetime64[ns]``.
        object1, object2: the two :class:`CdmObject`.
        creation_date: CREATION_DATE, UTC ``datetime64[ns]``.
        miss_distance: MISS_DISTANCE, m; relative_speed: RELATIVE_SPEED, m/s.
        collision_probability: COLLISION_PROBABILITY as given (None if absent) and
            ``collision_probability_method`` its method.
        hard_body_radius: combined hard-body radius from a ``COMMENT HBR = ...`` line, m
            (None if the message has none).
        originator, message_id, message_for: header fields.
    """

    tca: np.datetime64
    object1: CdmObject
    object2: CdmObject
    creation_date: np.datetime64
    miss_distance: float
    relative_speed: float
    collision_probability: float | None = None
    collision_probability_method: str = ""
    hard_body_radius: float | None = None
    originator: str = "rhoprop"
    message_id: str = "rhoprop"
    message_for: str = ""

    @property
    def lead_time(self) -> float:
        """TCA minus the creation date, s: how long the states were predicted ahead."""
        return float((self.tca - self.creation_date) / np.timedelta64(1, "ns")) * 1e-9

    def pc(
        self,
        hard_body_radius: float | None = None,
        *,
        shape: HardBodyShape = "circle",
        npd: NpdPolicy = "repair",
    ) -> PcResult:
        """The 2-D Pc (:func:`~rhoprop.conjunction.pc_2d`) of the message's own Gaussians
        (covariances in each object's RTN); ``hard_body_radius`` in m (default: the
        message's HBR comment); ``shape`` of the hard body and the ``npd`` policy as
        :func:`~rhoprop.conjunction.pc_2d` takes them."""
        from .probability import pc_2d

        hbr = self._hbr(hard_body_radius)
        a, b = self.object1, self.object2
        return pc_2d(
            a.position,
            a.velocity,
            a.covariance,
            b.position,
            b.velocity,
            b.covariance,
            hbr,
            frame="rtn",
            shape=shape,
            npd=npd,
        )

    def _hbr(self, hard_body_radius: float | None) -> float:
        hbr = self.hard_body_radius if hard_body_radius is None else hard_body_radius
        if hbr is None:
            raise ValueError(
                "the message gives no hard-body radius (no 'COMMENT HBR = ...' line): "
                "pass hard_body_radius= in m"
            )
        return float(hbr)


def _value(quantity: Any, scale: dict[str, float], what: str) -> float:
    """A ccsds-ndm quantity in SI: ``scale`` maps unit strings to factors."""
    if quantity is None:
        raise ValueError(f"CDM: {what} is missing")
    unit = getattr(quantity, "units", None)
    unit_text = "" if unit is None else str(getattr(unit, "value", unit))
    factor = scale.get(unit_text)
    if factor is None:
        raise ValueError(f"CDM: {what} has unit {unit_text!r}; expected one of {list(scale)}")
    return float(quantity.value) * factor


_KM = {"km": 1e3, "": 1e3}  # state vectors are km by the standard
_KM_S = {"km/s": 1e3, "": 1e3}
_M = {"m": 1.0, "": 1.0}
_M_S = {"m/s": 1.0, "": 1.0}
_SQ = {"m**2": 1.0, "m**2/s": 1.0, "m**2/s**2": 1.0, "": 1.0}


def _read_object(segment: Any) -> CdmObject:
    meta, data = segment.metadata, segment.data
    name = str(meta.object_name or meta.object_value.value)
    sv = data.state_vector
    where = f"object {name!r}"
    position = [_value(getattr(sv, k), _KM, f"{where} {k.upper()}") for k in ("x", "y", "z")]
    velocity = [
        _value(getattr(sv, k), _KM_S, f"{where} {k.upper()}") for k in ("x_dot", "y_dot", "z_dot")
    ]
    cov = np.zeros((6, 6))
    cm = data.covariance_matrix
    if cm is None:
        raise ValueError(f"CDM: {where} has no covariance")
    for i, row in enumerate(_COV_KEYS):
        for j, key in enumerate(row):
            cov[i, j] = cov[j, i] = _value(getattr(cm, key), _SQ, f"{where} {key.upper()}")
    extra = data.additional_parameters
    beta = getattr(extra, "cd_area_over_mass", None) if extra is not None else None
    frame = getattr(meta.ref_frame, "value", meta.ref_frame)
    return CdmObject(
        name=name,
        designator=str(meta.object_designator or ""),
        position=np.array(position),
        velocity=np.array(velocity),
        covariance=cov,
        ref_frame=str(frame),
        drag_parameter=None if beta is None else float(getattr(beta, "value", beta)),
        international_designator=str(meta.international_designator or ""),
    )


def _hbr_from_comments(text: str) -> float | None:
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.upper().startswith("COMMENT") or "<COMMENT>" in stripped.upper():
            match = _HBR.search(stripped)
            if match:
                unit = (match.group(2) or "m").lower()
                return float(match.group(1)) * (1e3 if unit == "km" else 1.0)
    return None


def read_cdm(source: str | Path) -> ConjunctionMessage:
    """Reads a CDM (KVN or XML, detected by content) from a path or from its text.

    Returns:
        :class:`ConjunctionMessage` in SI units (states converted from km and km/s).

    Raises:
        ValueError: not a CDM, missing fields, a non-inertial REF_FRAME.
        ImportError: ccsds-ndm is not installed.
    """
    text = _text_of(source)
    io, _formats, models = _library()
    try:
        message = io.from_string(text)
    except Exception as err:
        raise ValueError(f"CDM {_where(source)}: cannot parse: {err}") from err
    if not isinstance(message, models.Cdm):
        raise ValueError(f"{_where(source)} is a {type(message).__name__}, not a CDM")
    rel = message.body.relative_metadata_data
    segments = message.body.segment
    if len(segments) != 2:
        raise ValueError(f"CDM {_where(source)}: expected 2 objects, found {len(segments)}")
    header = message.header
    return ConjunctionMessage(
        tca=to_datetime64(str(rel.tca)),
        object1=_read_object(segments[0]),
        object2=_read_object(segments[1]),
        creation_date=to_datetime64(str(header.creation_date)),
        miss_distance=_value(rel.miss_distance, _M, "MISS_DISTANCE"),
        relative_speed=(
            _value(rel.relative_speed, _M_S, "RELATIVE_SPEED")
            if rel.relative_speed is not None
            else float("nan")
        ),
        collision_probability=(
            None if rel.collision_probability is None else float(rel.collision_probability)
        ),
        collision_probability_method=str(rel.collision_probability_method or ""),
        hard_body_radius=_hbr_from_comments(text),
        originator=str(header.originator or ""),
        message_id=str(header.message_id or ""),
        message_for=str(header.message_for or ""),
    )


def _text_of(source: str | Path) -> str:
    if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source):
        path = Path(source)
        if not path.is_file():
            raise ValueError(f"CDM file {str(path)!r} does not exist")
        return path.read_text()
    if isinstance(source, str):
        return source
    raise TypeError(f"source must be a path or the CDM's text, not {type(source).__name__}")


def _where(source: str | Path) -> str:
    return repr(str(source)) if isinstance(source, Path) or "\n" not in str(source) else "text"


def _iso(t: np.datetime64) -> str:
    """UTC epoch as CDMs write it, to the millisecond (rounded down)."""
    return str(np.asarray(t).astype("datetime64[ms]"))


def _build(message: ConjunctionMessage, m: Any) -> Any:
    """The ccsds-ndm object tree of ``message``."""

    def q(cls: str, value: float, unit: str, units: str) -> Any:
        return getattr(m, cls)(value=float(value), units=getattr(m, units)(unit))

    relative = relative_rtn(message)
    rel = m.RelativeMetadataData(
        tca=_iso(message.tca),
        miss_distance=q("LengthTypeUo", message.miss_distance, "m", "LengthUnits"),
        relative_speed=q("DvType", message.relative_speed, "m/s", "DvUnits"),
        relative_state_vector=m.RelativeStateVectorType(
            **{
                f"relative_position_{c}": q("LengthTypeUo", x, "m", "LengthUnits")
                for c, x in zip("rtn", relative[:3], strict=True)
            },
            **{
                f"relative_velocity_{c}": q("DvType", x, "m/s", "DvUnits")
                for c, x in zip("rtn", relative[3:], strict=True)
            },
        ),
        collision_probability=message.collision_probability,
        collision_probability_method=message.collision_probability_method or None,
    )
    segments = []
    for k, obj in enumerate((message.object1, message.object2), start=1):
        meta = m.CdmMetadata(
            object_value=m.ObjectType(f"OBJECT{k}"),
            object_designator=sanitise(obj.designator) or "UNKNOWN",
            catalog_name="SATCAT",
            object_name=sanitise(obj.name) or "UNKNOWN",
            international_designator=sanitise(obj.international_designator) or "UNKNOWN",
            ephemeris_name="NONE",
            covariance_method=m.CovarianceMethodType("CALCULATED"),
            maneuverable=m.ManeuverableType("N/A"),
            ref_frame=m.ReferenceFrameType(obj.ref_frame),
        )
        sv = m.CdmStateVectorType(
            **{
                k: q("PositionTypeUr", x / 1e3, "km", "PositionUnits")
                for k, x in zip(("x", "y", "z"), obj.position, strict=True)
            },
            **{
                k: q("VelocityTypeUr", x / 1e3, "km/s", "VelocityUnits")
                for k, x in zip(("x_dot", "y_dot", "z_dot"), obj.velocity, strict=True)
            },
        )
        unit_of = {0: ("M2Type", "m**2", "M2Units")}
        terms = {}
        for i, row in enumerate(_COV_KEYS):
            for j, key in enumerate(row):
                n_vel = (i >= 3) + (j >= 3)
                cls, unit, units = unit_of.get(
                    n_vel,
                    ("M2SType", "m**2/s", "M2SUnits")
                    if n_vel == 1
                    else ("M2S2Type", "m**2/s**2", "M2S2Units"),
                )
                terms[key] = q(cls, obj.covariance[i, j], unit, units)
        extra = None
        if obj.drag_parameter is not None:
            extra = m.AdditionalParametersType(
                cd_area_over_mass=q("M2KgType", obj.drag_parameter, "m**2/kg", "M2KgUnits")
            )
        data = m.CdmData(
            additional_parameters=extra,
            state_vector=sv,
            covariance_matrix=m.CdmCovarianceMatrixType(**terms),
        )
        segments.append(m.CdmSegment(metadata=meta, data=data))
    header = m.CdmHeader(
        creation_date=_iso(message.creation_date),
        originator=sanitise(message.originator) or "rhoprop",
        message_for=sanitise(message.message_for) or None,
        message_id=sanitise(message.message_id) or "rhoprop",
    )
    if message.hard_body_radius is not None:
        rel = replace(rel, comment=[f"HBR = {message.hard_body_radius:.6g} m"])
    return m.Cdm(header=header, body=m.CdmBody(relative_metadata_data=rel, segment=segments))


def relative_rtn(message: ConjunctionMessage) -> np.ndarray:
    """Object 2's state relative to object 1 in object 1's RTN frame (6,), m and m/s (the
    RELATIVE_POSITION/VELOCITY_R/T/N keywords)."""
    from ..frames import rtn_basis

    a, b = message.object1, message.object2
    basis = rtn_basis(a.position, a.velocity)
    return np.concatenate([basis @ (b.position - a.position), basis @ (b.velocity - a.velocity)])


def cdm_text(message: ConjunctionMessage, format: Literal["kvn", "xml"] = "kvn") -> str:
    """The CDM of ``message`` as KVN (``format="kvn"``) or XML text."""
    io, formats, models = _library()
    if format not in ("kvn", "xml"):
        raise ValueError(f"format must be 'kvn' or 'xml', not {format!r}")
    out = io.to_string(_build(message, models), formats.KVN if format == "kvn" else formats.XML)
    return str(out)


def write_cdm(
    message: ConjunctionMessage, path: str | Path, format: Literal["kvn", "xml"] | None = None
) -> Path:
    """Writes ``message`` as a CDM; ``format`` "kvn" or "xml" (default: from the suffix,
    ``.xml`` is XML, anything else KVN). Returns the path."""
    path = Path(path)
    fmt: Literal["kvn", "xml"] = format or ("xml" if path.suffix.lower() == ".xml" else "kvn")
    text = cdm_text(message, fmt)
    path.write_text(text)
    return path
