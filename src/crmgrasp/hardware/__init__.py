"""The hardware half: intrinsic contact sensing from fingertip wrenches
([`crmgrasp.hardware.contact_sensing`][]), the hand interface and the policy runner
([`crmgrasp.hardware.runner`][]), and a MuJoCo stand-in for Robonaut
([`crmgrasp.hardware.mujoco`][], extra ``crmgrasp[mujoco]``)."""
