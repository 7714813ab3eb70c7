"""The sky and day specs of a light result, to and from the document a project stores with
it (``settings`` of a result record), so that a project's sky and day results say how they
were traced to the app, the command line and notebooks alike."""

from __future__ import annotations

from typing import Any

from maizeviz.io.project import get
from maizeviz.light.specs import DaySpec, SkySpec

__all__ = ["run_settings", "settings_doc"]


def settings_doc(kind: str, settings: Any) -> dict | None:
    """The specs of a sky result (a :class:`SkySpec`) or a day result (``(DaySpec,
    SkySpec)``) as the JSON document a project stores with it, or None when they are not
    those."""
    from dataclasses import asdict, is_dataclass

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
                   text_or_none("weather"))


def run_settings(kind: str, result, stored: dict | None, where: str) -> Any:
    """The specs a sky or day result was traced with (a :class:`SkySpec`, or ``(DaySpec,
    SkySpec)`` for a day), as the app's light panel gives them for the same choice: from the
    stored ``settings`` document, else (an older record) the sky's from the result and None
    for a day. Bad stored settings: ProjectError naming ``where``."""
    if stored is not None:
        sky = _sky_spec(get(stored, "sky", dict, where=where), where)
        if kind == "sky":
            return sky
        return (_day_spec(get(stored, "day", dict, where=where), where), sky)
    if kind == "sky":
        s = result.sky
        return SkySpec(s.kind, s.n, "equal" if s.split == "equal" else "auto")
    return None
