"""Mitsuba variant choice (issue 5, "variants"): `llvm_ad_rgb` is 2–3× faster but needs a
libLLVM that works on this CPU, and a broken one may crash the process. So `auto` renders a tiny
scene with it in a child process first; on any failure it falls back to `scalar_rgb` with a
one-line notice. The verdict is cached in the virtual environment."""

import glob
import json
import os
import re
import subprocess
import sys

FAST, SAFE = "llvm_ad_rgb", "scalar_rgb"

_PROBE = """
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
scene = mi.load_dict({'type': 'scene', 'integrator': {'type': 'path'},
    'sensor': {'type': 'perspective', 'film': {'type': 'hdrfilm', 'width': 8, 'height': 8}},
    'light': {'type': 'constant'}, 'ball': {'type': 'sphere', 'bsdf': {'type': 'dielectric'}}})
import numpy as np
img = np.array(mi.render(scene, spp=4))
assert np.isfinite(img).all() and img.mean() > 0, 'bad image'
print('ok')
"""


def _cache_path():
    return os.path.join(sys.prefix, "polyphase_llvm_probe.json")


def llvm_candidates():
    """Values for DRJIT_LIBLLVM_PATH to try: the user's setting or Dr.Jit's own choice first,
    then every libLLVM >= 15 in the usual library folders, newest first."""
    found = []
    for folder in ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib"):
        for path in glob.glob(os.path.join(folder, "libLLVM-*.so*")) + glob.glob(
            os.path.join(folder, "libLLVM.so.*")
        ):
            m = re.search(r"libLLVM(?:-|\.so\.)(\d+)", os.path.basename(path))
            if m and int(m.group(1)) >= 15:
                found.append((int(m.group(1)), path))
    ordered = [None] + [p for _, p in sorted(found, key=lambda vp: (-vp[0], vp[1]))]
    return list(dict.fromkeys(ordered))


def _probe_one(lib, timeout):
    env = dict(os.environ)
    if lib is not None:
        env["DRJIT_LIBLLVM_PATH"] = lib
    try:
        r = subprocess.run(
            [sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=timeout, env=env
        )
    except subprocess.TimeoutExpired:
        return False, f"test render did not finish in {timeout:.0f} s"
    if r.returncode == 0 and r.stdout.strip().endswith("ok"):
        return True, ""
    last = (r.stderr.strip().splitlines() or [f"exit status {r.returncode}"])[-1]
    return False, f"test render failed: {last[:120]}"


def probe_llvm(timeout: float = 180.0):
    """(works, reason, library): renders a tiny scene with `llvm_ad_rgb` in a child process for
    each candidate libLLVM until one works; `library` is the DRJIT_LIBLLVM_PATH to use (None:
    Dr.Jit's default). The verdict is cached per Mitsuba version, user setting and set of
    libLLVM files, so installing one (the notice names the package) brings a new probe."""
    import mitsuba as mi

    if FAST not in mi.variants():
        return False, "this Mitsuba build has no llvm_ad_rgb", None
    candidates = llvm_candidates()
    libraries = ",".join(c for c in candidates if c is not None)
    key = f"{getattr(mi, '__version__', '?')}|{os.environ.get('DRJIT_LIBLLVM_PATH', '')}|{libraries}"
    try:
        with open(_cache_path(), "r", encoding="utf-8") as f:
            cached = json.load(f)
        if cached.get("key") == key:
            return bool(cached["works"]), cached.get("reason", ""), cached.get("library")
    except (OSError, ValueError, KeyError):
        pass
    works, reason, library = False, "no libLLVM >= 15 found", None
    for lib in candidates:
        ok, why = _probe_one(lib, timeout)
        if ok:
            works, reason, library = True, "", lib
            break
        reason = why
    try:
        with open(_cache_path(), "w", encoding="utf-8") as f:
            json.dump({"key": key, "works": works, "reason": reason, "library": library}, f)
    except OSError:
        pass
    return works, reason, library


def choose(requested: str, notice) -> str:
    """The variant to use for `requested` (`auto` or a Mitsuba variant name); sets it."""
    import mitsuba as mi

    if requested == "auto":
        works, reason, library = probe_llvm()
        if works and library is not None:
            os.environ["DRJIT_LIBLLVM_PATH"] = library
        variant = FAST if works else SAFE
        if not works:
            notice(
                f"note: {FAST} unavailable ({reason}); rendering with {SAFE}, 2-3x slower "
                "(on Debian bookworm: apt-get install libllvm19)"
            )
    else:
        if requested not in mi.variants():
            raise ValueError(f"unknown Mitsuba variant {requested!r} (have: {', '.join(mi.variants())})")
        variant = requested
    mi.set_variant(variant)
    return variant
