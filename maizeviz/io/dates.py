"""The calendar maizeviz reads: local dates of years 1 to 9999, whatever the source.

The date options (``--date``, the app's date fields) accept what :meth:`datetime.date.
fromisoformat` reads, years 0001 to 9999; a weather file's times must stay inside the same
years, so a file and an option never disagree on what a date is. Times are held in
microseconds (``datetime64[us]``, about +-290,000 years), never in pandas' default nanoseconds,
whose range (1677-09-21 to 2262-04-11) would silently wrap a year 2300 into 1716.
"""

from __future__ import annotations

from typing import Final

from maizeviz.errors import MaizevizError

#: First and last years a date may have (those of :class:`datetime.date`).
FIRST_YEAR, LAST_YEAR = 1, 9999
#: The unit of every time array: numpy datetime64 / pandas resolution.
TIME_UNIT: Final = "us"


def check_year(year: int, where: str, text: str,
               error: type[MaizevizError] = MaizevizError, quantity: str | None = "date") -> None:
    """Refuse a date whose year is outside :data:`FIRST_YEAR`..:data:`LAST_YEAR`.

    Parameters
    ----------
    year : the local year of the date
    where : what carries it, for the message ("weather.csv, line 4, column time")
    text : the date as written
    error : the MaizevizError subclass to raise
    """
    if not FIRST_YEAR <= int(year) <= LAST_YEAR:
        raise error(f"{where}: '{text}' is in the year {int(year)}; dates must be in the "
                    f"years {FIRST_YEAR:04d} to {LAST_YEAR}", quantity=quantity)
