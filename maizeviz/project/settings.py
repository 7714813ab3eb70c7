"""The sky and day specs of a light result, to and from the document a project stores with
it (``settings`` of a result record), so that a project's sky and day results say how they
were traced to the app, the command line and notebooks alike."""

from __future__ import annotations

from typing import Any

from maizeviz.errors import MaizevizError
from maizeviz.io.archive import ProjectError, get
from maizeviz.light.specs import DaySpec, OpticsSpec, SkySpec
from maizeviz.photosynthesis.c4 import LEGACY_TEMPERATURE_RESPONSE

__all__ = ["run_settings", "settings_doc"]


def settings_doc(kind: str, settings: Any) -> dict | None:
    """The specs of a sky result (a :class:`SkySpec`), a day result (``(DaySpec,
    SkySpec)``) or absorbed light (an :class:`OpticsSpec`) as the JSON document a project
    stores with it, or None when they are not those."""
    from dataclasses import asdict, is_dataclass

    if kind == "absorbed" and isinstance(settings, OpticsSpec):
        return {"optics": asdict(settings)}
    if kind == "sky" and is_dataclass(settings) and not isinstance(settings, type):
        return {"sky": asdict(settings)}
    if kind == "day" and isinstance(settings, tuple) and len(settings) == 2 and \
            all(is_dataclass(s) and not isinstance(s, type) for s in settings):
        return {"day": asdict(settings[0]), "sky": asdict(settings[1])}
    return None


def _sky_spec(doc: dict, where: str) -> SkySpec:
    at = f"{where}: the sky settings of a light result"
    return SkySpec(get(doc, "kind", str, where=at), get(doc, "directions", int, where=at),
                   get(doc, "split", str, where=at))


def _day_spec(doc: dict, where: str) -> DaySpec:
    at = f"{where}: the day settings of a light result"

    def text_or_none(key: str):
        value = doc.get(key)
        return None if value is None else get(doc, key, str, where=at)

    return DaySpec(get(doc, "date", str, where=at), float(get(doc, "lat", (int, float), where=at)),
                   float(get(doc, "lon", (int, float), where=at)), get(doc, "tz", str, where=at),
                   float(get(doc, "step_min", (int, float), where=at)), text_or_none("start"),
                   text_or_none("end"), float(get(doc, "linke", (int, float), where=at)),
                   float(get(doc, "par_factor", (int, float), where=at)),
                   text_or_none("weather"), _choice(doc, "diffuse", ("sky", "perez"), at))


def _choice(doc: dict, key: str, allowed: tuple[str, ...], at: str) -> str:
    value = get(doc, key, str, allowed[0], at)
    if value not in allowed:
        raise ProjectError(f"{at}: '{key}' is '{value[:40]}', not one of {', '.join(allowed)}")
    return value


def run_settings(kind: str, result, stored: dict | None, where: str) -> Any:
    """The specs a sky or day result was traced with (a :class:`SkySpec`, or ``(DaySpec,
    SkySpec)`` for a day), as the app's light panel gives them for the same choice: from the
    stored ``settings`` document, else (an older record) the sky's from the result and None
    for a day; for absorbed light, its :class:`OpticsSpec` (from the result when not stored).
    Bad stored settings: ProjectError naming ``where``."""
    if kind == "absorbed":
        return _optics_spec(stored, result, where)
    if stored is not None:
        sky = _sky_spec(get(stored, "sky", dict, where=where), where)
        if kind == "sky":
            return sky
        return (_day_spec(get(stored, "day", dict, where=where), where), sky)
    if kind == "sky":
        s = result.sky
        return SkySpec(s.kind, s.n, "equal" if s.split == "equal" else "auto")
    return None


def _optics_spec(stored: dict | None, light, where: str) -> OpticsSpec:
    at = f"{where}: the optics settings of an absorbed-light result"
    if stored is None:
        o = light.optics
        return OpticsSpec(light.band, o.reflectance, o.transmittance, o.ground_reflectance)
    doc = get(stored, "optics", dict, where=at)

    def number_or_none(key: str):
        value = doc.get(key)
        return None if value is None else float(get(doc, key, (int, float), where=at))

    spec = OpticsSpec(get(doc, "band", str, where=at), number_or_none("reflectance"),
                      number_or_none("transmittance"), number_or_none("ground_reflectance"),
                      number_or_none("direct_w_m2"),
                      float(get(doc, "diffuse_w_m2", (int, float), 0.0, at)),
                      get(doc, "depth", int, 3, at), get(doc, "seed", int, 0, at),
                      tuple(tuple(r) for r in get(doc, "ranks", list, [], at)
                            if isinstance(r, list)),
                      get(doc, "photosynthesis", str, "", at),
                      float(get(doc, "temperature_c", (int, float), 25.0, at)),
                      tuple((str(r[0]), float(r[1])) for r in
                            get(doc, "photosynthesis_params", list, [], at)
                            if isinstance(r, list) and len(r) == 2 and isinstance(r[0], str)
                            and isinstance(r[1], (int, float)) and not isinstance(r[1], bool)),
                      # saved before the C4 temperature response was a choice: CLM 4.5's
                      get(doc, "c4_temperature", str, LEGACY_TEMPERATURE_RESPONSE, at))
    try:
        spec.optics()
        spec.leaf_model()
    except (MaizevizError, TypeError, ValueError) as exc:
        raise ProjectError(f"{at}: {exc}") from None
    return spec
