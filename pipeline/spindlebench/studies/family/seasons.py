"""Climate tables: each month's mean daily low and high ambient, and the seasons they form.

Shipped climates live in ``scenarios/seasons/<name>.toml``; a study names one of them or
gives a path to its own table.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import SEASONS_DIR
from spindlebench.formats.toml import Table, load_toml, one_of

MONTHS = ("Jan", "Feb", "Mar", "Apr", "May", "Jun",
          "Jul", "Aug", "Sep", "Oct", "Nov", "Dec")



@dataclass(frozen=True)
class MonthAmbient:
    """A month's climatological mean daily minimum and maximum air temperature."""

    month: str
    low_C: float  # noqa: N815 (unit suffix, as in the scenarios)
    high_C: float  # noqa: N815


@dataclass(frozen=True)
class Climate:
    """Monthly ambient table of one place, plus which months make up which season."""

    name: str
    source: str
    path: Path
    months: dict[str, MonthAmbient]
    seasons: dict[str, tuple[str, ...]]

    def season_of(self, month: str) -> str:
        for season, months in self.seasons.items():
            if month in months:
                return season
        raise SpindlebenchError(f"{self.path}: month '{month}' belongs to no season")


def resolve_climate_path(name: str, relative_to: Path | None = None) -> Path:
    """A shipped climate name (``chongqing``) or a path to a climate TOML file."""
    candidate = Path(name)
    if candidate.suffix == ".toml":
        if not candidate.is_absolute() and relative_to is not None:
            candidate = relative_to / candidate
        return candidate
    return SEASONS_DIR / f"{name}.toml"


def available_climates() -> list[str]:
    return sorted(path.stem for path in SEASONS_DIR.glob("*.toml"))


def load_climate(path: str | Path) -> Climate:
    """Read and check a climate table; every error names the file and the key."""
    path = Path(path)
    if not path.exists():
        shipped = ", ".join(available_climates()) or "none"
        raise SpindlebenchError(f"{path}: climate file not found (shipped climates: {shipped})")
    root = Table(load_toml(path, "climate"), path)
    info = root.table("climate")
    name = info.get("name", str)
    source = info.get("source", str)
    info.get("hemisphere", str, default="north",
             check=lambda v: one_of(v, ("north", "south")))
    info.finish()

    month_table = root.table("months")
    months: dict[str, MonthAmbient] = {}
    for month in month_table.names():
        if month not in MONTHS:
            raise month_table.error(month, f"not a month (use one of {', '.join(MONTHS)})")
        entry = month_table.table(month)
        low = entry.get("low_C", float, check=_plausible_celsius)
        high = entry.get("high_C", float, check=_plausible_celsius)
        entry.finish()
        if high < low:
            raise entry.error("high_C", f"{high} is below low_C {low}")
        months[month] = MonthAmbient(month, low, high)
    month_table.finish()
    missing = [m for m in MONTHS if m not in months]
    if missing:
        raise root.error("months", f"missing month(s) {', '.join(missing)}")

    season_table = root.table("seasons")
    seasons: dict[str, tuple[str, ...]] = {}
    seen: dict[str, str] = {}
    for season in season_table.names():
        members = season_table.get_list(
            season, str, check=lambda m: None if m in MONTHS else "not a month name")
        for month in members:
            if month in seen:
                raise season_table.error(season, f"{month} is already in season '{seen[month]}'")
            seen[month] = season
        seasons[season] = tuple(members)
    season_table.finish()
    unassigned = [m for m in MONTHS if m not in seen]
    if unassigned:
        raise root.error("seasons", f"month(s) {', '.join(unassigned)} belong to no season")
    root.finish()
    return Climate(name, source, path, months, seasons)


def _plausible_celsius(value: float) -> str | None:
    if value > 70:
        return f"{value} looks like Kelvin or Fahrenheit; give degC"
    if value < -60:
        return f"{value} degC is implausibly cold"
    return None
