"""The hardware half: intrinsic contact sensing from fingertip wrenches
(:mod:`crmgrasp.hardware.contact_sensing`), the hand interface and the policy runner
(:mod:`crmgrasp.hardware.runner`), and a MuJoCo stand-in for Robonaut
(:mod:`crmgrasp.hardware.mujoco`, extra ``crmgrasp[mujoco]``)."""
