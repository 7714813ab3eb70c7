"""The sun's options, shared by ``maizeviz light`` and ``maizeviz instrument``: explicit angles
(``--sun-zenith``, ``--sun-azimuth``), or a place, a date and a clock time through pvlib."""

from __future__ import annotations

import argparse

from maizeviz.cli.common import NUMBER_ARG
from maizeviz.errors import MaizevizError

#: What to give when no sun is given.
WHERE_IS_THE_SUN = ("where is the sun? give --sun-zenith and --sun-azimuth, or --date, --time "
                    "(or --solar-noon), --lat, --lon and --tz")


def add_sun_options(p: argparse.ArgumentParser, altitude: bool = True) -> None:
    """Add the sun's options in a group of their own; ``--altitude`` (site altitude, m) too
    unless ``altitude`` is False (a command that puts it with other options)."""
    sun = p.add_argument_group("sun (explicit angles, or place + date + time through pvlib)")
    sun.add_argument("--sun-zenith", type=NUMBER_ARG, metavar="DEG", help="zenith angle, degrees")
    sun.add_argument("--sun-azimuth", type=NUMBER_ARG, metavar="DEG",
                     help="azimuth, degrees clockwise from north (field y = north by default)")
    sun.add_argument("--date", help="YYYY-MM-DD")
    sun.add_argument("--time", help="local clock time HH:MM (or HH:MM+08:00 with its offset)")
    sun.add_argument("--solar-noon", action="store_true", help="the true solar noon of --date")
    sun.add_argument("--lat", type=NUMBER_ARG, help="latitude, degrees north")
    sun.add_argument("--lon", type=NUMBER_ARG, help="longitude, degrees east")
    sun.add_argument("--tz", default=None,
                     help="time zone, e.g. Asia/Shanghai (default UTC, or the offset of --time)")
    if altitude:
        add_altitude_option(sun)


def add_altitude_option(group) -> None:
    """``--altitude``: the site's altitude in m (clear sky and sun positions)."""
    group.add_argument("--altitude", type=NUMBER_ARG, default=0.0, metavar="M",
                       help="site altitude, m (clear sky and sun positions; default 0)")


def sun_place_given(args: argparse.Namespace) -> bool:
    """Whether any of a place-and-time sun's options was given."""
    return any(v is not None for v in (args.date, args.time, args.lat, args.lon)) or \
        args.solar_noon


def sun_from_options(args: argparse.Namespace):
    """The sun the options give (a :class:`~maizeviz.light.sources.sun.Sun`); refused in one
    line when they give none, half of one, or two (angles and a place)."""
    from maizeviz.light.sources.sun import Sun, sun_at

    explicit = args.sun_zenith is not None or args.sun_azimuth is not None
    place = sun_place_given(args)
    if explicit and place:
        raise MaizevizError("give either --sun-zenith/--sun-azimuth or a place and time, not both")
    if explicit:
        if args.sun_zenith is None or args.sun_azimuth is None:
            raise MaizevizError("give both --sun-zenith and --sun-azimuth")
        return Sun(args.sun_zenith, args.sun_azimuth)
    if not place:
        raise MaizevizError(WHERE_IS_THE_SUN)
    if args.date is None or args.lat is None or args.lon is None:
        raise MaizevizError("a sun from a place needs --date, --lat and --lon (and --time or "
                            "--solar-noon, --tz)")
    if not args.time and not args.solar_noon:
        raise MaizevizError("give --time HH:MM or --solar-noon for one sun, or --day (or "
                            "--from/--to) for a period")
    return sun_at(args.date, args.time, args.lat, args.lon, args.tz, args.solar_noon,
                  args.altitude)
