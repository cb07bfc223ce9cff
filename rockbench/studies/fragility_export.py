"""Fitted fragility curves in two risk tools' formats (``docs/fragility-export.md``).

The curves are rockbench's lognormal fits (:func:`rockbench.studies.fragility.fit_lognormal`):
per backend, P(overturning | IM = x) = Phi(ln(x / median) / beta), the median in the intensity
measure's unit (:data:`rockbench.studies.fragility.MEASURES`: PGA in m/s^2, PGV in m/s) and the
dispersion beta [-]; one limit state, :data:`LIMIT_STATE`. Two pure writers:

* :func:`to_nrml` - OpenQuake's fragility model, NRML 0.5, one continuous ``logncdf``
  fragility function per curve. OpenQuake's continuous lognormal takes the **mean and standard
  deviation of the IML itself** (not of ln IML), in OpenQuake's units (PGA in g, PGV in cm/s):
  for ln X ~ N(ln median, beta^2), mean = median exp(beta^2 / 2) and
  stddev = mean sqrt(exp(beta^2) - 1) (:func:`lognormal_moments`), which OpenQuake turns back
  into sigma^2 = ln(1 + stddev^2 / mean^2) and median = mean^2 / sqrt(mean^2 + stddev^2)
  (:func:`lognormal_from_moments`): exactly the curve fitted.
* :func:`to_pelicun_csv` - pelicun 3's damage (fragility) model table: one row per curve,
  ``LS1-Family`` "lognormal", ``LS1-Theta_0`` the median, ``LS1-Theta_1`` beta.

:func:`curves_from_analysis` builds the curves from :func:`rockbench.studies.fragility.analyse`'s
output (``Fragility.analysis``).
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence, TextIO

from ..constants import G_STANDARD
from ..errors import ParameterError, check_finite
from .fragility import MEASURES

__all__ = ["LIMIT_STATE", "NRML_NAMESPACE", "OPENQUAKE_IMT", "PELICUN_DEMAND",
           "PELICUN_COLUMNS", "FragilityCurve", "curves_from_analysis", "lognormal_moments",
           "lognormal_from_moments", "to_nrml", "to_pelicun_csv", "write_fragility_exports"]

#: The one limit state of a rocking frame's fragility.
LIMIT_STATE = "overturning"
#: The XML namespace of NRML 0.5 (OpenQuake engine >= 1.7).
NRML_NAMESPACE = "http://openquake.org/xmlns/nrml/0.5"
#: rockbench measure -> (OpenQuake IMT, OpenQuake's unit, factor from rockbench's unit to it):
#: PGA m/s^2 -> g (standard gravity 9.80665 m/s^2), PGV m/s -> cm/s.
OPENQUAKE_IMT: dict[str, tuple[str, str, float]] = {
    "pga": ("PGA", "g", 1.0 / G_STANDARD),
    "pgv": ("PGV", "cm/s", 100.0),
}
#: rockbench measure -> (pelicun demand type, pelicun unit name). pelicun converts the unit to
#: its SI base on loading; the medians are written in rockbench's units.
PELICUN_DEMAND: dict[str, tuple[str, str]] = {
    "pga": ("Peak Ground Acceleration", "mps2"),
    "pgv": ("Peak Ground Velocity", "mps"),
}
#: Columns of pelicun 3's fragility table for one limit state, in order.
PELICUN_COLUMNS = ("ID", "Incomplete", "Demand-Type", "Demand-Unit", "Demand-Offset",
                   "Demand-Directional", "LS1-Family", "LS1-Theta_0", "LS1-Theta_1",
                   "LS1-DamageStateWeights")
#: OpenQuake ids: letters, digits, dash, underscore, at most 100 characters.
_OQ_ID = re.compile(r"^[A-Za-z0-9_-]{1,100}$")


@dataclass(frozen=True)
class FragilityCurve:
    """One fitted lognormal fragility curve of overturning: ``id`` (the backend's name, or a
    taxonomy string: letters, digits, ``-``, ``_``, at most 100 characters), ``median`` theta
    (> 0) [IM unit: m/s^2 for PGA, m/s for PGV], ``dispersion`` beta (> 0) [-], ``measure``
    ``pga`` or ``pgv`` (:data:`OPENQUAKE_IMT`: the measures both tools read)."""

    id: str
    median: float
    dispersion: float
    measure: str = "pga"

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not _OQ_ID.match(self.id):
            raise ParameterError("id", self.id, "letters, digits, '-' or '_', 1 to 100 "
                                 "characters (an OpenQuake taxonomy id)")
        for name in ("median", "dispersion"):
            x = check_finite(name, getattr(self, name))
            if x <= 0.0:
                raise ParameterError(name, getattr(self, name), "> 0 (a regular fit)")
            object.__setattr__(self, name, x)
        if self.measure not in OPENQUAKE_IMT:
            raise ParameterError("measure", self.measure, f"one of {', '.join(OPENQUAKE_IMT)} "
                                 "(the measures both tools read)")

    @property
    def unit(self) -> str:
        """The intensity measure's unit in rockbench (m/s^2 or m/s)."""
        return MEASURES[self.measure][1]

    def probability(self, x: float) -> float:
        """P(overturning | IM = x) = Phi(ln(x / median) / dispersion), x [IM unit] > 0."""
        return 0.5 * math.erfc(-math.log(x / self.median) / (self.dispersion * math.sqrt(2.0)))


def curves_from_analysis(analysis: Mapping[str, Any], measure: str | None = None
                         ) -> list[FragilityCurve]:
    """The curves of :func:`rockbench.studies.fragility.analyse`'s output: one per backend with
    a regular fit (finite median and dispersion), in the analysis's order, against ``measure``
    (default: the analysis's intensity measure; another one is read from the analysis's
    intensity-measure table, ``analysis["measures"]``). Backends without one (no run
    overturned, or every run) are left out; ParameterError if none is left."""
    key = analysis.get("intensity", {}).get("key", "pga")
    fits = {name: b for name, b in analysis.get("backends", {}).items()}
    if measure is not None and measure != key:
        if measure not in MEASURES:
            raise ParameterError("measure", measure, f"one of {', '.join(MEASURES)}")
        table = (analysis.get("measures") or {}).get("backends", {})
        fits = {name: table[name]["fits"][measure] for name in fits
                if measure in table.get(name, {}).get("fits", {})}
        key = measure
    out = []
    for name, b in fits.items():
        med, disp = b.get("median"), b.get("dispersion")
        if med is not None and disp is not None and math.isfinite(med) and math.isfinite(disp):
            out.append(FragilityCurve(str(name), float(med), float(disp), key))
    if not out:
        raise ParameterError("analysis", "no backend with a regular fit",
                             "at least one backend with a finite median and dispersion")
    return out


def lognormal_moments(median: float, dispersion: float) -> tuple[float, float]:
    """(mean, standard deviation) of X with ln X ~ N(ln median, dispersion^2): mean = median
    exp(beta^2 / 2), stddev = mean sqrt(exp(beta^2) - 1) [unit of median]."""
    b2 = dispersion * dispersion
    mean = median * math.exp(0.5 * b2)
    return mean, mean * math.sqrt(math.expm1(b2))


def lognormal_from_moments(mean: float, stddev: float) -> tuple[float, float]:
    """(median, dispersion) of the lognormal X with that mean and standard deviation:
    beta^2 = ln(1 + stddev^2 / mean^2), median = mean / sqrt(1 + stddev^2 / mean^2) (the
    reading of OpenQuake's ``logncdf``; inverse of :func:`lognormal_moments`)."""
    r2 = (stddev / mean) ** 2
    return mean / math.sqrt(1.0 + r2), math.sqrt(math.log1p(r2))


def _checked(curves: Iterable[FragilityCurve]) -> list[FragilityCurve]:
    out = list(curves) if not isinstance(curves, FragilityCurve) else [curves]
    if not out or not all(isinstance(c, FragilityCurve) for c in out):
        raise ParameterError("curves", curves, "one or more FragilityCurve")
    ids = [c.id for c in out]
    if len(set(ids)) != len(ids):
        raise ParameterError("curves", ids, "curves with distinct ids")
    if len({c.measure for c in out}) != 1:
        raise ParameterError("curves", sorted({c.measure for c in out}),
                             "curves of one intensity measure")
    return out


def _number(x: float) -> str:
    """A float written so that it reads back exactly (shortest repr)."""
    return repr(float(x))


def _open(path_or_file: str | os.PathLike | TextIO, writer) -> None:
    if hasattr(path_or_file, "write"):
        writer(path_or_file)
        return
    with open(path_or_file, "w", encoding="utf-8", newline="") as f:
        writer(f)


def to_nrml(curves: Sequence[FragilityCurve] | FragilityCurve,
            path_or_file: str | os.PathLike | TextIO, *, id: str = "rockbench_overturning",
            min_iml: float, max_iml: float, assets_category: str = "buildings",
            loss_category: str = "structural", description: str | None = None,
            no_damage_limit: float | None = None) -> None:
    """Write ``curves`` as an OpenQuake fragility model (NRML 0.5) to a path or a text file.

    ``<fragilityModel id assetCategory lossCategory>`` holds a ``<description>``, the
    ``<limitStates>`` (:data:`LIMIT_STATE`) and one ``<fragilityFunction id format="continuous"
    shape="logncdf">`` per curve with ``<imls imt minIML maxIML [noDamageLimit]>`` and
    ``<params ls mean stddev>``: the mean and standard deviation of the IML
    (:func:`lognormal_moments`) in OpenQuake's unit of the IMT (:data:`OPENQUAKE_IMT`).
    ``min_iml`` < ``max_iml`` (and ``no_damage_limit``) are in rockbench's unit of the
    measure (m/s^2 or m/s), > 0, converted like the moments: the range of intensities over
    which OpenQuake uses the functions (typically the range of the fit's runs; outside it
    OpenQuake holds each curve at its value at the nearer end). ``no_damage_limit``, in
    [``min_iml``, ``max_iml``): at and below it OpenQuake's probability is 0. OpenQuake clamps
    the intensity to minIML before it compares it with the limit, so a limit below
    ``min_iml`` would have no effect at all: refused.
    ``loss_category``: one of OpenQuake's "structural", "nonstructural", "contents",
    "business_interruption"."""
    curves = _checked(curves)
    if not isinstance(id, str) or not _OQ_ID.match(id):
        raise ParameterError("id", id, "letters, digits, '-' or '_', 1 to 100 characters")
    if loss_category not in ("structural", "nonstructural", "contents", "business_interruption"):
        raise ParameterError("loss_category", loss_category, "structural, nonstructural, "
                             "contents or business_interruption")
    lo, hi = check_finite("min_iml", min_iml), check_finite("max_iml", max_iml)
    if not 0.0 < lo < hi:
        raise ParameterError("max_iml", max_iml, f"> min_iml = {lo:g} > 0")
    ndl = None
    if no_damage_limit is not None:
        ndl = check_finite("no_damage_limit", no_damage_limit)
        if not lo <= ndl < hi:
            raise ParameterError("no_damage_limit", no_damage_limit,
                                 f"in [min_iml, max_iml) = [{lo:g}, {hi:g}) (OpenQuake clamps "
                                 "the intensity to minIML first: a lower limit has no effect)")
    measure = curves[0].measure
    imt, oq_unit, factor = OPENQUAKE_IMT[measure]
    name, unit = MEASURES[measure][:2]
    if description is None:
        description = (f"rockbench lognormal fragility of {LIMIT_STATE}: {name} [{unit} in "
                       f"rockbench, {oq_unit} here]; " + "; ".join(
                           f"{c.id} median {c.median:.6g} {unit}, beta {c.dispersion:.4g}"
                           for c in curves))
    ET.register_namespace("", NRML_NAMESPACE)
    q = f"{{{NRML_NAMESPACE}}}"
    root = ET.Element(q + "nrml")
    model = ET.SubElement(root, q + "fragilityModel", {"id": id, "assetCategory":
                                                        str(assets_category),
                                                        "lossCategory": loss_category})
    ET.SubElement(model, q + "description").text = description
    ET.SubElement(model, q + "limitStates").text = LIMIT_STATE
    for c in curves:
        ff = ET.SubElement(model, q + "fragilityFunction",
                           {"id": c.id, "format": "continuous", "shape": "logncdf"})
        imls = {"imt": imt, "minIML": _number(lo * factor), "maxIML": _number(hi * factor)}
        if ndl is not None:
            imls["noDamageLimit"] = _number(ndl * factor)
        ET.SubElement(ff, q + "imls", imls)
        mean, std = lognormal_moments(c.median * factor, c.dispersion)
        ET.SubElement(ff, q + "params", {"ls": LIMIT_STATE, "mean": _number(mean),
                                         "stddev": _number(std)})
    ET.indent(root, space="    ")
    text = '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode")
    _open(path_or_file, lambda f: f.write(text + "\n"))


def to_pelicun_csv(curves: Sequence[FragilityCurve] | FragilityCurve,
                   path_or_file: str | os.PathLike | TextIO, *, id_prefix: str = "",
                   directional: bool = True) -> None:
    """Write ``curves`` as a pelicun 3 damage model (fragility) table: columns
    :data:`PELICUN_COLUMNS`, one row per curve: ``ID`` ``id_prefix`` + the curve's id (no
    ``-``: pelicun splits IDs there),
    ``Incomplete`` 0, ``Demand-Type`` and ``Demand-Unit`` (:data:`PELICUN_DEMAND`),
    ``Demand-Offset`` 0, ``Demand-Directional`` 1 (the frame rocks in the plane of the
    component of ground motion it was analysed for: pelicun compares the curve with that
    direction's demand, as fitted; 0 with ``directional=False``: pelicun then compares it with
    max(direction 1, direction 2) times its ``NonDirectionalMultipliers``, 1.2 by default
    (FEMA P-58), which shifts the curve unless the assessment sets the multiplier to 1),
    ``LS1-Family`` "lognormal", ``LS1-Theta_0`` the median [Demand-Unit], ``LS1-Theta_1``
    beta [-], ``LS1-DamageStateWeights`` empty (one damage state, DS1 = overturned)."""
    curves = _checked(curves)
    demand, unit = PELICUN_DEMAND[curves[0].measure]
    rows = [{"ID": f"{id_prefix}{c.id}", "Incomplete": 0, "Demand-Type": demand,
             "Demand-Unit": unit, "Demand-Offset": 0,
             "Demand-Directional": 1 if directional else 0, "LS1-Family": "lognormal",
             "LS1-Theta_0": _number(c.median), "LS1-Theta_1": _number(c.dispersion),
             "LS1-DamageStateWeights": ""} for c in curves]
    for r in rows:
        if "," in r["ID"] or "-" in r["ID"]:
            raise ParameterError("id", r["ID"], "no ',' nor '-' in a pelicun ID (pelicun reads "
                                 "'-' as the separator of its index levels)")

    def write(f: TextIO) -> None:
        w = csv.DictWriter(f, fieldnames=list(PELICUN_COLUMNS), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)

    _open(path_or_file, write)


def write_fragility_exports(analysis: Mapping[str, Any], folder: str | os.PathLike, *,
                            stem: str = "fragility", runs: Any = None,
                            record_ims: Any = None) -> dict[str, Any]:
    """Write the curves of ``analysis`` (:func:`curves_from_analysis`) in both formats into
    ``folder`` (created): ``<stem>.xml`` (:func:`to_nrml`, model id ``stem``) and
    ``<stem>.csv`` (:func:`to_pelicun_csv`). The measure is the analysis's when the tools know
    it (:data:`OPENQUAKE_IMT`: PGA, PGV), else PGA from its intensity-measure table. The range
    of the NRML functions is the range of the runs' intensities in that measure: ``runs`` (the
    runs frame: scale, record) times ``record_ims`` (the records' measures) when both are given,
    else the analysis's grid (its own measure only). Returns {file name: path}."""
    from pathlib import Path

    key = analysis.get("intensity", {}).get("key", "pga")
    measure = key if key in OPENQUAKE_IMT else "pga"
    curves = curves_from_analysis(analysis, None if measure == key else measure)
    if runs is not None and record_ims is not None and len(runs):
        of = dict(zip(record_ims["record"], record_ims[measure]))
        x = [float(s) * float(of[r]) for s, r in zip(runs["scale"], runs["record"])]
        lo, hi = min(x), max(x)
    elif measure == key:
        lo, hi = float(analysis["grid"][0]), float(analysis["grid"][-1])
    else:
        raise ParameterError("record_ims", None, f"the runs and the records' measures, to give "
                             f"the range of the {MEASURES[measure][0]} curves")
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    mid = stem if _OQ_ID.match(stem) else "rockbench_overturning"
    xml, table = root / f"{stem}.xml", root / f"{stem}.csv"
    to_nrml(curves, xml, id=mid, min_iml=lo, max_iml=hi if hi > lo else lo * 1.000001)
    to_pelicun_csv(curves, table)
    return {xml.name: xml, table.name: table}


def _text(writer, *args, **kwargs) -> str:
    """What ``writer`` writes, as a string (for tests and the docs)."""
    buf = io.StringIO()
    writer(*args, buf, **kwargs)
    return buf.getvalue()
