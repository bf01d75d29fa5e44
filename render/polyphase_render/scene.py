"""The resolved scene of a run folder (`DIR/scene.toml`): phases with their render properties,
the domain box, the background phase, and the optional `[render]` hints a scene file may carry
to override the presets (camera, opaque phases, tank, ground, lighting, absorption length)."""

import math
import tomllib
from dataclasses import dataclass, field
from typing import Optional

import numpy as np


#: The `render.opaque` entry that names every phase.
ALL_PHASES = "*"


class SceneError(Exception):
    """`scene.toml` is missing or lacks what rendering needs."""


@dataclass
class Phase:
    """One phase: name, linear RGB colour in [0, 1], index of refraction, density."""

    name: str
    color: tuple
    ior: float
    density: float


@dataclass
class RenderHints:
    """Optional `[render]` table of a scene file; every field has a default from the domain."""

    camera_origin: Optional[np.ndarray] = None  # world position of the eye
    camera_target: Optional[np.ndarray] = None  # point looked at (default: domain centre)
    up: Optional[np.ndarray] = None  # default: -gravity if the scene has one, else +y
    fov: float = 35.0  # horizontal field of view, degrees
    opaque: Optional[list] = None  # phase names drawn as rough plastic, "*" all (default: none; slabs: all)
    tank: bool = False  # draw the domain walls as thin glass
    ground: bool = True  # checkered ground plane under the domain
    absorption_length: Optional[float] = None  # metres over which a liquid transmits its colour
    ambient: float = 0.5  # radiance of the constant environment
    light: float = 1.0  # radiance of the rectangular area light above the domain
    smooth: bool = True  # interpolated vertex normals (crease angle 60 degrees)
    fps: int = 24  # movie frame rate
    cutaway: Optional[tuple] = None  # (point, unit normal): triangles beyond the plane are not drawn


@dataclass
class Scene:
    """What the renderer needs from `scene.toml`."""

    name: str
    phases: list
    background: int
    lo: np.ndarray
    hi: np.ndarray
    slab: bool
    hints: RenderHints = field(default_factory=RenderHints)

    @property
    def extent(self) -> np.ndarray:
        """Edge lengths of the domain box."""
        return self.hi - self.lo

    @property
    def center(self) -> np.ndarray:
        """Centre of the domain box."""
        return 0.5 * (self.lo + self.hi)

    def phase_index(self, name: str) -> int:
        """Index of the phase called `name`; `SceneError` if there is none."""
        for i, p in enumerate(self.phases):
            if p.name == name:
                return i
        raise SceneError(f"no phase named {name!r}")

    def opaque_ids(self) -> set:
        """Phases drawn as opaque plastic: the hint's list (`"*"` names every phase, the
        background included: a foam's cells, whose names a generator chose), or for a 2D slab
        every phase but the background (a slab two cells thick shows no colour as a transparent
        liquid)."""
        if self.hints.opaque is not None:
            if ALL_PHASES in self.hints.opaque:
                return set(range(len(self.phases)))
            return {self.phase_index(n) for n in self.hints.opaque}
        if self.slab:
            return {i for i in range(len(self.phases)) if i != self.background}
        return set()

    def absorption_length(self, liquid_volume: Optional[float] = None) -> float:
        """Distance over which a liquid's transmittance equals its colour: the hint, else the
        edge of a cube of the mean liquid phase volume (`liquid_volume`), so small drops and
        whole tanks both show their colour without turning black; a tenth of the domain when
        there is no liquid."""
        if self.hints.absorption_length is not None:
            return self.hints.absorption_length
        if liquid_volume is not None and liquid_volume > 0:
            return liquid_volume ** (1.0 / 3.0)
        return 0.1 * float(self.extent.max())


def _vec3(table, key, where):
    v = table.get(key)
    if v is None:
        return None
    if not (isinstance(v, list) and len(v) == 3 and all(isinstance(c, (int, float)) for c in v)):
        raise SceneError(f"{where}.{key} must be a list of three numbers")
    a = np.array(v, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise SceneError(f"{where}.{key} must be finite")
    return a


def _hints(doc) -> RenderHints:
    t = doc.get("render", {})
    if not isinstance(t, dict):
        raise SceneError("[render] must be a table")
    known = set(RenderHints.__dataclass_fields__)
    known |= {"camera_origin", "camera_target"}
    unknown = sorted(set(t) - known)
    if unknown:
        raise SceneError(f"[render]: unknown field {unknown[0]!r}")
    h = RenderHints()
    h.camera_origin = _vec3(t, "camera_origin", "render")
    h.camera_target = _vec3(t, "camera_target", "render")
    h.up = _vec3(t, "up", "render")
    for key in ("fov", "absorption_length", "ambient", "light"):
        if key in t:
            v = t[key]
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise SceneError(f"render.{key} must be a non-negative number")
            setattr(h, key, float(v))
    for key in ("tank", "ground", "smooth"):
        if key in t:
            if not isinstance(t[key], bool):
                raise SceneError(f"render.{key} must be true or false")
            setattr(h, key, t[key])
    if "fps" in t:
        if not isinstance(t["fps"], int) or t["fps"] < 1:
            raise SceneError("render.fps must be a positive integer")
        h.fps = t["fps"]
    if "opaque" in t:
        if not (isinstance(t["opaque"], list) and all(isinstance(n, str) for n in t["opaque"])):
            raise SceneError("render.opaque must be a list of phase names")
        h.opaque = list(t["opaque"])
    if "cutaway" in t:
        c = t["cutaway"]
        if not isinstance(c, dict) or set(c) != {"point", "normal"}:
            raise SceneError("render.cutaway must be a table with point and normal")
        point = _vec3(c, "point", "render.cutaway")
        normal = _vec3(c, "normal", "render.cutaway")
        length = float(np.linalg.norm(normal))
        if length == 0:
            raise SceneError("render.cutaway.normal must not be zero")
        h.cutaway = (point, normal / length)
    if h.fov <= 0 or h.fov >= 180:
        raise SceneError("render.fov must be between 0 and 180 degrees")
    return h


def _gravity(doc):
    """Gravity vector if the scene states one (top level or in a `[physics]`/`[solver]` table)."""
    for table in (doc, doc.get("physics", {}), doc.get("solver", {})):
        if isinstance(table, dict) and "gravity" in table:
            return _vec3(table, "gravity", "scene")
    return None


def parse_scene(text: str) -> Scene:
    """Parses the text of a resolved scene file."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"scene.toml is not valid TOML: {e}") from None
    try:
        phases = [
            Phase(
                name=str(p["name"]),
                color=tuple(float(c) for c in p.get("color", [0.8, 0.8, 0.8])),
                ior=float(p.get("ior", 1.33)),
                density=float(p.get("density", 1000.0)),
            )
            for p in doc["phases"]
        ]
        domain = doc["domain"]
        lo = np.array(domain["lo"], dtype=np.float64)
        hi = np.array(domain["hi"], dtype=np.float64)
        background_name = doc.get("background", phases[0].name if phases else "")
    except (KeyError, TypeError, ValueError, IndexError) as e:
        raise SceneError(f"scene.toml lacks or mistypes {e}") from None
    if not phases:
        raise SceneError("scene.toml has no [[phases]]")
    if lo.shape != (3,) or hi.shape != (3,) or np.any(hi <= lo):
        raise SceneError("scene.toml: [domain] lo/hi must be three numbers with lo < hi")
    for p in phases:
        if len(p.color) != 3 or p.ior <= 0:
            raise SceneError(f"phase {p.name!r}: color needs three values and ior must be > 0")
    scene = Scene(
        name=str(doc.get("name", "scene")),
        phases=phases,
        background=0,
        lo=lo,
        hi=hi,
        slab=bool(domain.get("slab", False)),
        hints=_hints(doc),
    )
    scene.background = scene.phase_index(background_name)
    if scene.hints.up is None:
        g = _gravity(doc)
        scene.hints.up = -g if g is not None and np.linalg.norm(g) > 0 else np.array([0.0, 1.0, 0.0])
    n = np.linalg.norm(scene.hints.up)
    if n == 0:
        raise SceneError("render.up must not be zero")
    scene.hints.up = scene.hints.up / n
    if scene.hints.opaque is not None:
        scene.opaque_ids()  # names checked here, before any frame is rendered
    return scene


def load_scene(path) -> Scene:
    """Reads `scene.toml`; `SceneError` with a one-line reason if it cannot be used."""
    try:
        with open(path, "r", encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise SceneError(f"cannot read {path}: {e.strerror or e}") from None
    return parse_scene(text)
