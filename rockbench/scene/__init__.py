"""The scene model every backend builds from: structures, devices, ground motions."""

from .contact import Contact
from .devices import Devices
from .motion import GroundMotion, Record, RickerPulse, WithVertical, make_pulse
from .records import load_at2, load_columns, load_record
from .scene import Scene, apply_overrides, builtin_scenes, load_scene, save_scene
from .structure import Block, Frame

__all__ = ["Block", "Frame", "Devices", "Contact", "Scene", "GroundMotion", "RickerPulse", "Record",
           "WithVertical", "make_pulse", "load_at2", "load_columns", "load_record", "load_scene",
           "save_scene", "builtin_scenes", "apply_overrides"]
