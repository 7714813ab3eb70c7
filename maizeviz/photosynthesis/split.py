"""Assimilation of triangles partly in the sun: each part at its own light.

A triangle of area ``A`` whose primary rays lit ``S`` of it (``f = S / A``) absorbed
``E_dir`` W from the direct beam, all on that sunlit part, and ``E_bg`` W of everything else
(the diffuse sky, light scattered by leaves and soil), taken as spread evenly over it. Its
gross assimilation is ::

    f A g(E_bg / A + E_dir / (f A))  +  (1 - f) A g(E_bg / A)

``g`` a leaf model's light response per m2 of leaf. On the sunlit part ``E_dir / (f A)`` is
exactly the beam's absorbed flux on that triangle's orientation, ``(1 - sigma) I_b |n . s|``,
the quantity WOFOST and de Pury & Farquhar (1997) integrate analytically over leaf angles.
Feeding the mean ``(E_dir + E_bg) / A`` to ``g`` instead overstates a concave response
(Jensen's inequality): +7 to +15 % per leaf on a spherical canopy.

References
----------
de Pury, D. G. G. & Farquhar, G. D. (1997). Simple scaling of photosynthesis from leaves to
canopies without the errors of big-leaf models. Plant, Cell & Environment 20, 537-557.
Spitters, C. J. T. (1986). Agricultural and Forest Meteorology 38, 231-242.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Protocol

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.photosynthesis.c4 import C4Leaf
from maizeviz.photosynthesis.wofost import WofostLeaf

#: Leaf models by name.
MODELS = ("c4", "wofost")


class LeafModel(Protocol):
    """What a leaf model offers (:class:`~maizeviz.photosynthesis.c4.C4Leaf`,
    :class:`~maizeviz.photosynthesis.wofost.WofostLeaf`)."""

    name: str

    @property
    def label(self) -> str:
        """The model in words, with its temperature response where it has a choice."""

    def gross(self, par_w_m2, temp_c=25.0):
        """Gross assimilation, umol CO2/m2 leaf/s, at absorbed PAR ``par_w_m2`` (W/m2)."""

    def respiration(self, temp_c):
        """Leaf respiration, umol CO2/m2 leaf/s."""

    def as_dict(self) -> dict[str, float | str]:
        """The model's name (``model``) and parameters."""


def leaf_model(name: str = "c4", **params) -> LeafModel:
    """A leaf photosynthesis model by name, its parameters replacing the defaults.

    Parameters
    ----------
    name : {"c4", "wofost"}
        Collatz et al.'s C4 leaf, or WOFOST's light response.
    **params
        Parameters of the model's class (:class:`~maizeviz.photosynthesis.c4.C4Leaf`,
        :class:`~maizeviz.photosynthesis.wofost.WofostLeaf`); None values are left out.

    Returns
    -------
    LeafModel
        The model.

    Raises
    ------
    MaizevizError
        An unknown model or parameter, or a value out of range.
    """
    key = str(name).strip().lower()
    classes: dict[str, type[C4Leaf | WofostLeaf]] = {"c4": C4Leaf, "wofost": WofostLeaf}
    if key not in classes:
        raise MaizevizError(f"unknown photosynthesis model '{name}' (known: "
                            f"{', '.join(MODELS)})", quantity="photosynthesis")
    cls = classes[key]
    given = {k: v for k, v in params.items() if v is not None and k != "model"}
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(given) - known)
    if unknown:
        raise MaizevizError(f"the {key} model has no parameter {', '.join(unknown)} (its "
                            f"parameters: {', '.join(sorted(known))})",
                            quantity="photosynthesis")
    return cls(**given)


def as_leaf_model(model: LeafModel | str) -> LeafModel:
    """A leaf model, or the model a name gives with its defaults.

    Parameters
    ----------
    model : LeafModel or {"c4", "wofost"}
        A model (returned as it is), or its name (:func:`leaf_model`).

    Returns
    -------
    LeafModel
        The model.

    Raises
    ------
    MaizevizError
        An unknown name, or something that is neither a name nor a leaf model.
    """
    if isinstance(model, str):
        return leaf_model(model)
    if not callable(getattr(model, "gross", None)):
        raise MaizevizError(f"a leaf model is a name ({', '.join(MODELS)}) or a model from "
                            f"maizeviz.leaf_model(...), not {type(model).__name__}",
                            quantity="photosynthesis")
    return model


#: Parameters of maizeviz 0.2's C4 records that now come with the temperature response.
_LEGACY_C4_KEYS = ("s1", "s2", "s3", "s4", "s5", "s6")


def model_from_dict(record: dict) -> LeafModel:
    """The leaf model an :meth:`as_dict` record describes.

    A C4 record without ``temperature_response`` was written by maizeviz 0.2, which computed
    with CLM 4.5's response and recorded its constants (``s1``-``s6``): it is read as that
    (:data:`~maizeviz.photosynthesis.c4.LEGACY_TEMPERATURE_RESPONSE`).
    """
    from maizeviz.photosynthesis.c4 import LEGACY_TEMPERATURE_RESPONSE

    if not isinstance(record, dict) or not isinstance(record.get("model"), str):
        raise MaizevizError("a photosynthesis record needs its model's name",
                            quantity="photosynthesis")
    params = {k: v for k, v in record.items() if k != "model"}
    if str(record["model"]).strip().lower() == "c4":
        params = {k: v for k, v in params.items() if k not in _LEGACY_C4_KEYS}
        params.setdefault("temperature_response", LEGACY_TEMPERATURE_RESPONSE)
    return leaf_model(record["model"], **params)


def split_assimilation(model: LeafModel, area_m2, sunlit_m2, direct_w, background_w,
                       temp_c=25.0):
    """Gross assimilation of each triangle, umol CO2/s, its sunlit and shaded parts each at
    its own light (see the module docstring).

    Parameters
    ----------
    model : LeafModel
    area_m2 : (F,) float64, triangle areas, m2 (one side)
    sunlit_m2 : (F,) float64, area in the direct beam, m2 (at most ``area_m2`` for the
        gross to stay within the model's light-saturated rate)
    direct_w : (F,) float64, W of PAR absorbed from the direct beam (on the sunlit part)
    background_w : (F,) float64, W of PAR absorbed from everything else (spread evenly)
    temp_c : leaf temperature, C (scalar)

    Returns
    -------
    (F,) float64, umol CO2/s per triangle
    """
    area = np.asarray(area_m2, dtype=np.float64)
    # the traced sunlit area is sampled from the triangle, at most its area
    # (maizeviz.light.trace.sunlit); the result is linear in it at the beam's exact flux, so
    # its noise averages out over triangles. Not capped here: capping a noisy estimate would
    # raise the flux of those capped and bias a concave response low
    lit = np.maximum(np.asarray(sunlit_m2, dtype=np.float64), 0.0)
    direct = np.asarray(direct_w, dtype=np.float64)
    # a beam that reached a triangle lit it: no direct flux without sunlit area
    lit = np.where((direct > 0) & (lit <= 0), area, lit)
    safe = np.where(area > 0, area, 1.0)
    bg = np.asarray(background_w, dtype=np.float64) / safe
    sun = np.where(lit > 0, direct / np.where(lit > 0, lit, 1.0), 0.0)
    shaded = model.gross(bg, temp_c)
    sunny = model.gross(bg + sun, temp_c)
    return np.where(area > 0, lit * sunny + (area - lit) * shaded, 0.0)


def mean_assimilation(model: LeafModel, area_m2, absorbed_w, temp_c=25.0):
    """What feeding each triangle's mean absorbed PAR to ``model`` gives, umol CO2/s (F,):
    the error :func:`split_assimilation` avoids, kept for comparison."""
    area = np.asarray(area_m2, dtype=np.float64)
    safe = np.where(area > 0, area, 1.0)
    return np.where(area > 0, area * model.gross(np.asarray(absorbed_w) / safe, temp_c), 0.0)
