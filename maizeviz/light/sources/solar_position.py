"""The sun's position by NREL's SPA, from pvlib's numpy implementation, without pandas.

pvlib's ``get_solarposition`` (method "nrel_numpy") and ``sun_rise_set_transit_spa`` wrap the
module ``pvlib.spa``, which needs numpy only; importing the ``pvlib`` package, though, imports
pandas, scipy and the rest of pvlib (1 to 2 s here), more than a whole K = 4 sun takes to
trace. For one sun this module runs pvlib's own ``spa`` file on its own (the package is not
imported) with the inputs pvlib's wrappers give it, so the angles are pvlib's to the last bit
(``tests/core/test_solar_position.py`` compares them with ``get_solarposition`` and
``sun_rise_set_transit_spa``). Sun tracks over a period still go through pvlib's wrappers
(:mod:`maizeviz.light.sources.irradiance`), which need pandas anyway.

References
----------
- Reda, I. & Andreas, A. (2004). Solar position algorithm for solar radiation applications.
  Solar Energy 76(5), 577-589.
- Holmgren, W. F., Hansen, C. W. & Mikofski, M. A. (2018). pvlib python: a python package for
  modeling solar energy systems. Journal of Open Source Software 3(29), 884.
"""

from __future__ import annotations

import datetime as _dt
import functools
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

from maizeviz.errors import MaizevizError

#: What pvlib's wrappers pass to the SPA when not told otherwise (pvlib 0.16, the only minor
#: release pyproject.toml allows: 0.15 gives other suns): ``spa_python``'s delta_t (s) and
#: temperature (deg C) and its refraction at the horizon (deg)
DELTA_T_S = 67.0
TEMPERATURE_C = 12.0
ATMOS_REFRACT_DEG = 0.5667
_EPOCH = _dt.datetime(1970, 1, 1, tzinfo=_dt.UTC)
_NS = 10**9


@functools.cache
def spa() -> ModuleType:
    """pvlib's ``spa`` module: the package's own when already imported, else :func:`spa_file`.

    Raises
    ------
    MaizevizError
        pvlib is not installed.
    """
    return sys.modules.get("pvlib.spa") or spa_file()


def spa_file() -> ModuleType:
    """pvlib's ``spa.py`` run on its own (numpy only), not through the ``pvlib`` package.

    Raises
    ------
    MaizevizError
        pvlib is not installed.
    """
    found = importlib.util.find_spec("pvlib")        # finds the package without running it
    folders = list(found.submodule_search_locations or []) if found else []
    source = next((Path(f) / "spa.py" for f in folders if (Path(f) / "spa.py").is_file()), None)
    if source is None:                                 # not a plain install: the package's way
        try:
            from pvlib import spa as module
        except ImportError:
            raise MaizevizError("the sun's position from a date needs pvlib (pip install "
                                "pvlib)", quantity="sun") from None
        return module
    spec = importlib.util.spec_from_file_location("maizeviz._pvlib_spa", source)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def pressure_pa(altitude_m: float) -> float:
    """Standard-atmosphere pressure (Pa) at ``altitude_m`` above sea level.

    pvlib's ``atmosphere.alt2pres``, which ``get_solarposition`` uses for the refraction.
    """
    return 100 * ((44331.514 - altitude_m) / 11880.516) ** (1 / 0.1902632)


def unix_seconds(when: _dt.datetime) -> float:
    """Seconds since 1970-01-01 UTC of a timezone-aware ``when`` (microseconds kept)."""
    return (when - _EPOCH).total_seconds()


def position(unixtime: float, lat: float, lon: float,
             altitude_m: float = 0.0) -> tuple[float, float]:
    """Apparent (refraction-corrected) zenith and azimuth (degrees) at one instant.

    Parameters
    ----------
    unixtime : seconds since 1970-01-01 UTC
    lat, lon : degrees north and east
    altitude_m : m above sea level

    Returns
    -------
    (zenith_deg, azimuth_deg), azimuth clockwise from north: pvlib's ``get_solarposition``
    columns ``apparent_zenith`` and ``azimuth``.
    """
    out = spa().solar_position_numpy(np.array([unixtime], dtype=float), lat, lon, altitude_m,
                                     pressure_pa(altitude_m) / 100, TEMPERATURE_C, DELTA_T_S,
                                     ATMOS_REFRACT_DEG, 1, False, False)
    return float(out[0][0]), float(out[4][0])


def transit_ns(day: _dt.date, lat: float, lon: float) -> int:
    """The sun's transit (true solar noon) on the local calendar ``day``, ns since 1970 UTC.

    pvlib's ``sun_rise_set_transit_spa``: the SPA is given that day's 00:00 labelled UTC and
    its seconds become whole nanoseconds as pvlib's ``pd.to_datetime(..., unit="ns")`` makes
    them (truncated), as a Python integer: every year from 1 to 9999, where pandas'
    nanoseconds stop at 1677 and 2262.
    """
    midnight = float((day - _EPOCH.date()).days * 86400)
    transit, _rise, _set = spa().transit_sunrise_sunset(np.array([midnight]), lat, lon,
                                                        DELTA_T_S, 1)
    return int(float(transit[0]) * 1e9)


def iso_ns(ns: int, where: _dt.tzinfo) -> str:
    """ISO 8601 text of ``ns`` nanoseconds since 1970 UTC in zone ``where``, as pandas writes
    a Timestamp: 9 decimals when nanoseconds are there, 6 for microseconds, else none."""
    seconds, rest = divmod(ns, _NS)
    local = (_EPOCH + _dt.timedelta(seconds=seconds)).astimezone(where)
    text = local.isoformat()
    fraction = f".{rest:09d}" if rest % 1000 else (f".{rest // 1000:06d}" if rest else "")
    return text[:19] + fraction + text[19:]
