"""Type stubs of the compiled module `poser._poser` (mirrors crates/poser-py/src/lib.rs)."""

from os import PathLike
from typing import Any, Literal, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

class PoserError(Exception):
    """A poser run failed (I/O, a renderer, a scene the command cannot handle)."""

class SceneError(PoserError):
    """The scene is invalid; `.diagnostics` holds each error and warning."""

    diagnostics: list[Diagnostic]

class Diagnostic:
    """One diagnostic: where (file, line, column), what, and the hint."""

    severity: Literal["error", "warning"]
    code: str
    message: str
    file: str | None
    line: int | None
    column: int | None
    help: str | None
    rendered: str

ScalarValue = bool | int | float | str

def load(
    path: str | PathLike[str],
    set: dict[str, ScalarValue | Sequence[ScalarValue]] | None = None,
) -> Scene:
    """Load, validate and resolve a scene file; `set` overrides values like `--set KEY=VALUE`.

    Raises `SceneError` (with `.diagnostics`) when the scene is invalid.
    """

class Scene:
    """A loaded, validated scene: the resolved model every poser command works on."""

    @property
    def name(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def warnings(self) -> list[Diagnostic]: ...
    @property
    def files(self) -> list[str]: ...
    @property
    def poses(self) -> list[dict[str, Any]]:
        """Rig poses: `index`, `name`, `time`, `strip`, `world_from_rig` (4×4 float64)."""
    @property
    def cameras(self) -> list[dict[str, Any]]:
        """The rig's cameras as truth.json gives them (pixel centres at +0.5, COLMAP's)."""
    def explain(self) -> str:
        """The resolved model's key numbers (what `poser explain` prints)."""
    def to_dict(self) -> dict[str, Any]:
        """The whole resolved model (what `poser explain --json` prints)."""
    def project(
        self,
        points: npt.ArrayLike,
        camera: str | None = None,
        frame: Literal["camera", "world"] = "camera",
        pose: int = 0,
        channel: Literal["r", "g", "b"] = "g",
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.str_]]:
        """(N, 3) metres, or one point as (3,) → ((N, 2) pixels, NaN where none; (N,) status:
        "ok", "off_sensor", …)."""
    def truth(self) -> dict[str, Any]:
        """Ground truth of every image (truth.json), point columns as numpy arrays."""
    def plan(self) -> dict[str, Any]:
        """The survey plan (`poser plan --json`, its `survey`)."""
    def dive(self) -> dict[str, Any]:
        """The dive plan and verdict (`poser dive --json`)."""
    def render(
        self,
        pose: int = 0,
        camera: str | None = None,
        samples: int | None = None,
        scale: float | None = None,
    ) -> npt.NDArray[np.float32]:
        """One native render: (H, W, 3) float32 linear RGB, row 0 at the top."""
    def compile(self, backend: Literal["mitsuba", "blender"], out_dir: str | PathLike[str]) -> None:
        """Write the scene for Mitsuba 3 or Blender into `out_dir` (as `poser compile`)."""
