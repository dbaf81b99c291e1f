"""Device profiles: the facts about a device model (units, papers, pens, link, motion) as data, read from TOML.

``model`` holds the data classes and limits, ``toml`` the profile format and the built-in profiles, ``vpype``
vpype's device configuration files.
"""

from pixelpen.profiles.model import (
    PROTOCOLS,
    DeviceProfile,
    LinkSettings,
    MotionLimits,
    Paper,
    ServoSettings,
)
from pixelpen.profiles.toml import builtin_profiles, load_profile
from pixelpen.profiles.vpype import load_vpype_config, parse_length_mm

__all__ = [
    "PROTOCOLS", "DeviceProfile", "LinkSettings", "MotionLimits", "Paper", "ServoSettings", "builtin_profiles",
    "load_profile", "load_vpype_config", "parse_length_mm",
]
