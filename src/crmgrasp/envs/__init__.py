"""Gymnasium environments over a task's kernel: [`CRMGraspEnv`][] (one episode),
[`CRMGraspVectorEnv`][] (N episodes batched) and the [`KOrderHistory`][]
wrapper. Importing this package registers ``crmgrasp/PaperBox-v0``."""

from crmgrasp.envs.single import ENV_ID, CRMGraspEnv, KOrderHistory
from crmgrasp.envs.vector import CRMGraspVectorEnv

__all__ = ["ENV_ID", "CRMGraspEnv", "CRMGraspVectorEnv", "KOrderHistory"]
