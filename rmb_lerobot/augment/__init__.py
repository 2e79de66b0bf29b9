"""SART data augmentation around one demonstration (RMB's RoboManipAug).

- :mod:`~rmb_lerobot.augment.reverse`: playing a recording backwards, key by key;
- :mod:`~rmb_lerobot.augment.regions`: acceptable regions (YAML, proposals at gripper events);
- :mod:`~rmb_lerobot.augment.sart`: driving out to samples on each region's sphere in the
  simulator, reversing, appending the rest of the demo, writing RMB episodes
  (what ``rmb-augment`` runs).
"""

from rmb_lerobot.augment.regions import (
    Region,
    dump_regions,
    gripper_events,
    load_regions,
    propose_regions,
)
from rmb_lerobot.augment.reverse import (
    derive_relative,
    invert_rel_pose,
    reverse_recording,
    reverse_relative,
)
from rmb_lerobot.augment.sart import (
    AugmentConfig,
    Augmenter,
    SampleResult,
    propose_demo_regions,
    sample_rotation,
    sample_sphere_surface,
)

__all__ = [
    "AugmentConfig",
    "Augmenter",
    "Region",
    "SampleResult",
    "derive_relative",
    "dump_regions",
    "gripper_events",
    "invert_rel_pose",
    "load_regions",
    "propose_demo_regions",
    "propose_regions",
    "reverse_recording",
    "reverse_relative",
    "sample_rotation",
    "sample_sphere_surface",
]
