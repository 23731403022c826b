"""Gymnasium environments over a task's kernel: [`CRMGraspEnv`][] (one episode),
[`CRMGraspVectorEnv`][] (N episodes batched), the [`KOrderHistory`][]
wrapper, and the continuous action space ([`ContinuousCRMEnv`][], [`FlatCRMAction`][]).
Importing this package registers the environments (``crmgrasp/PaperBox-v0``, ...)."""

from crmgrasp.envs.continuous import ContinuousCRMEnv, FlatCRMAction
from crmgrasp.envs.single import ENV_ID, CRMGraspEnv, KOrderHistory
from crmgrasp.envs.vector import CRMGraspVectorEnv

__all__ = ["ENV_ID", "CRMGraspEnv", "CRMGraspVectorEnv", "KOrderHistory", "ContinuousCRMEnv", "FlatCRMAction"]
