"""Device profiles: the facts about a device model (units, papers, pens, link, motion) as data, read from TOML."""

from pixelpen.profiles.model import (
    DeviceProfile,
    LinkSettings,
    Paper,
    ServoSettings,
    builtin_profiles,
    load_profile,
    load_vpype_config,
    parse_length_mm,
)

__all__ = [
    "DeviceProfile", "LinkSettings", "Paper", "ServoSettings", "builtin_profiles", "load_profile",
    "load_vpype_config", "parse_length_mm",
]
