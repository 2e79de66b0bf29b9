"""SART data augmentation around one demonstration (RMB's RoboManipAug)."""
