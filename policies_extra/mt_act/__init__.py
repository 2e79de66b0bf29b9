"""MT-ACT (Bharadhwaj et al., ICRA 2024) as a LeRobot plugin (``--policy.type=mt_act``)."""

from .configuration_mt_act import MTACTConfig
from .modeling_mt_act import MTACTPolicy
from .processor_mt_act import make_mt_act_pre_post_processors

__all__ = ["MTACTConfig", "MTACTPolicy", "make_mt_act_pre_post_processors"]
