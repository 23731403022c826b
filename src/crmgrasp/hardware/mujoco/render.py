"""Headless rendering of the MuJoCo stand-in to PNG and GIF.

MuJoCo picks its OpenGL backend when it is first imported, from ``MUJOCO_GL``;
[`require_mujoco`][crmgrasp.hardware.mujoco.require_mujoco] sets it to ``egl`` unless the user set
it. Where EGL is missing, ``crmgrasp show --hand mujoco`` retries once in a
child process with ``MUJOCO_GL=osmesa``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_path
from crmgrasp._validation import CrmgraspError
from crmgrasp.hardware.mujoco.hand import MujocoHand
from crmgrasp.tasks import Task

__all__ = ["Recorder", "render", "save_png", "save_gif", "show"]


class _Camera:
    """A renderer bound to one model, with the top-down scene camera."""

    def __init__(self, hand: MujocoHand, width: int, height: int) -> None:
        try:
            self.renderer = hand.mj.Renderer(hand.model, height, width)
        except Exception as exc:
            gl = os.environ.get("MUJOCO_GL", "")
            raise CrmgraspError(
                f"headless MuJoCo rendering failed with MUJOCO_GL={gl or '(unset)'}: {exc}; set MUJOCO_GL=egl "
                "(or osmesa) before mujoco is first imported"
            ) from None
        self.hand = hand

    def __call__(self) -> np.ndarray:
        self.renderer.update_scene(self.hand.data, camera=self.hand.camera)
        return np.array(self.renderer.render())


def render(hand: MujocoHand, width: int = 480, height: int = 320) -> np.ndarray:
    """One RGB frame (``height x width x 3``, uint8) of the scene from above."""
    cam = _Camera(hand, width, height)
    try:
        return cam()
    finally:
        cam.renderer.close()


class Recorder:
    """Collects a frame every ``every`` control ticks of ``hand`` (install with [`attach`][])."""

    def __init__(self, hand: MujocoHand, every: int = 10, width: int = 360, height: int = 240) -> None:
        self.camera = _Camera(hand, width, height)
        self.every, self._n = every, 0
        self.frames: list[np.ndarray] = []

    def attach(self) -> Recorder:
        """Start recording (takes the first frame now)."""
        self.camera.hand.on_tick = self
        self.frames.append(self.camera())
        return self

    def __call__(self, hand: Any) -> None:
        self._n += 1
        if self._n % self.every == 0:
            self.frames.append(self.camera())

    def close(self) -> None:
        """Stop recording and free the renderer."""
        self.camera.hand.on_tick = None
        self.camera.renderer.close()


def save_png(frame: np.ndarray, path: str | os.PathLike[str]) -> Path:
    """Write an RGB frame as PNG, atomically."""
    from PIL import Image

    with atomic_path(path) as tmp:
        Image.fromarray(frame).save(tmp, format="PNG")
    return Path(path)


def save_gif(frames: list[np.ndarray], path: str | os.PathLike[str], fps: float = 10.0) -> Path:
    """Write RGB frames as a looping GIF, atomically."""
    from PIL import Image

    if not frames:
        raise CrmgraspError("no frames to write")
    images = [Image.fromarray(f) for f in frames]
    with atomic_path(path) as tmp:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
    return Path(path)


def show(task: Task, start: Any, crm: Any, out: str | os.PathLike[str], rng: np.random.Generator) -> str:
    """Render the MuJoCo scene from ``start`` (and the motion of ``crm``) to ``out``:
    a ``.png`` of the final scene or a ``.gif`` of the whole motion (a planar or a spatial
    task: [`mujoco_hand`][crmgrasp.hardware.mujoco.spatial.mujoco_hand]). Returns a summary line."""
    path = Path(out)
    if path.suffix.lower() not in {".png", ".gif"}:
        raise CrmgraspError(f"--out must end in .png or .gif with the mujoco backend, got {path.name!r}")
    from crmgrasp.hardware.mujoco.spatial import mujoco_hand

    hand = mujoco_hand(task, start, rng)
    size = {"width": 480, "height": 320}  # the PNG's and the GIF's frames alike
    rec = Recorder(hand, every=6, **size).attach() if path.suffix.lower() == ".gif" else None
    error = hand.execute(crm) if crm is not None else None
    what = f"CRM {crm} -> {error.name.lower()}" if error is not None else "scene"
    key = "a red, b green, palm orange"  # the stand-in's colours (hardware.mujoco.model)
    if rec is not None:
        rec.close()
        band = caption(f"{task.name} on MuJoCo: {what}; {key}", rec.frames[0].shape[1])
        save_gif([np.vstack([band, f]) for f in rec.frames], path, fps=15)
    else:
        frame = render(hand, **size)
        save_png(np.vstack([caption(f"{task.name} on MuJoCo: {what}; {key}", frame.shape[1]), frame]), path)
    return f"{task.name} on MuJoCo: {what}; wrote {path.resolve()}"


def caption(text: str, width: int, height: int = 26) -> np.ndarray:
    """A white band ``width`` pixels wide holding ``text`` (an image's label), as RGB uint8
    rows to stack above a rendered frame."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    fig.text(0.01, 0.5, text, va="center", ha="left", fontsize=8)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:height, :width, :3].copy()
