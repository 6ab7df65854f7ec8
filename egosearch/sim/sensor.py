"""The training sensor: a fast depth image plus the target's segmentation mask.

Camera convention (every other module relies on it)
---------------------------------------------------
- World frame: metres, z up (see :mod:`egosearch.scene.parts`).
- ``yaw`` is the heading in the world xy plane: ``yaw = 0`` looks along +x, positive yaw turns
  counter-clockwise seen from above (``yaw = pi/2`` looks along +y).
- ``pitch`` tilts the optical axis: positive looks up, ``-pi/2`` looks straight down. No roll: the
  image's horizontal axis stays parallel to the floor.
- Camera axes in the world frame::

      forward = ( cos(yaw) cos(pitch),  sin(yaw) cos(pitch),  sin(pitch))
      right   = ( sin(yaw),            -cos(yaw),             0         )
      up      = right x forward = (-cos(yaw) sin(pitch), -sin(yaw) sin(pitch), cos(pitch))

  Looking straight down (``pitch = -pi/2``) the top of the image points along the heading.
- Image row 0 is the top, column 0 the left. Pixels are square; ``fov_deg`` is the HORIZONTAL
  field of view, so the focal length in pixels is ``f = (W / 2) / tan(fov / 2)`` and a W x H
  image spans ``2 atan(H / 2f)`` vertically (90 deg both ways for the default square image).
- One ray through each pixel CENTRE: pixel (row i, column j) looks along
  ``forward + (j + 0.5 - W/2) / f * right + (H/2 - i - 0.5) / f * up``.
- ``depth`` is z-depth (distance along the optical axis, like OpenGL / pyrender depth), in
  metres, clipped to ``max_depth``; rays that hit nothing, or hit beyond ``max_depth``, read
  ``max_depth``. Surfaces are seen from both sides (no back-face culling).
- ``mask[i, j]`` is True where the target is the nearest surface (occlusion respected) and
  nearer than ``max_depth``. The target also occludes the house in ``depth``.
- Geometry nearer than :data:`NEAR_PLANE` (1 mm, in z-depth) is not seen (only matters for a
  camera inside or touching a part).

Backends (all give the same picture up to float rounding on triangle edges)
---------------------------------------------------------------------------
- ``"raster"`` (the default): a small z-buffer rasteriser written in C (``raster.c``), built at
  ``pip install`` into the package (``setup.py``, ``-O3 -march=native``; ``EGOSEARCH_NATIVE_BUILD=0``
  builds it for any CPU) and loaded with ctypes (no Python headers, no extra packages). When the
  install could not build it (no compiler there), or built it for another CPU or an older
  ``raster.c``, it is compiled on first use with ``$CC``, cc, gcc or clang into
  ``$EGOSEARCH_CACHE_DIR`` or ``~/.cache/egosearch`` if a compiler is found; else the sensor warns
  once and uses Embree. It
  culls whole parts against the view frustum (bounding spheres), clips triangles against a near
  plane, and samples exactly the pixel centres (inclusive edge test, perspective-correct 1/z),
  so it is a drop-in for ray casting at a fraction of the cost.
- ``"embree"``: Embree 4 (the library shipped inside the ``embreex`` wheel) called directly
  through ctypes with 16-ray packets over 4x4 pixel tiles; the static house is ONE geometry
  in one scene built once, the target a second tiny scene traced only for the tiles covering
  its projected bounding box.
- ``"embreex"``: ``embreex``'s own per-ray ``run(query="DISTANCE")``; the slowest, the last
  resort when neither of the above can be loaded (its near plane is 0, not ``NEAR_PLANE``).

Measured on one core (``taskset -c 0``, Xeon Sapphire Rapids, 100x100, target set):
~0.18 ms/frame for the 4.6k-triangle ``kitchen_living``; ~0.4 ms/frame for a cluttered synthetic
11k-triangle room (raster), against ~1.4 ms (embree packets) and ~2.4 ms (embreex ``run``).

Mask feature (paper section 4.1)
--------------------------------
:func:`mask_feature` gives ``[xc, yc, r, alpha, M~ (5x5, row-major, top row first), visible]``:
the paper's 29-d feature plus a 30th entry, OUR addition: a visibility flag (1.0 when any mask
pixel is set), so that "target at the image centre" and "target not visible" differ.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import hashlib
import math
import os
import subprocess
import tempfile
import time
import warnings

import numpy as np

from egosearch.scene.meshes import part_mesh, scene_meshes
from egosearch.scene.parts import Part, Scene
from egosearch.sim import rasterbuild
from egosearch.sim.body import IMAGE_SIZE

DEFAULT_WIDTH = IMAGE_SIZE
DEFAULT_HEIGHT = IMAGE_SIZE
DEFAULT_FOV_DEG = 90.0
DEFAULT_MAX_DEPTH = 5.0
#: Near clipping plane of the rasteriser (m): geometry nearer than this is not seen.
NEAR_PLANE = 1e-3
MASK_GRID = 5
MASK_FEATURE_DIM = 4 + MASK_GRID * MASK_GRID + 1
BACKENDS = ("raster", "embree", "embreex")


# ----------------------------------------------------------------------------------------------
# Camera geometry
# ----------------------------------------------------------------------------------------------

def camera_axes(yaw: float, pitch: float) -> np.ndarray:
    """3x3 matrix whose ROWS are the camera's right, up and forward axes in the world frame."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    return np.array([[sy, -cy, 0.0],
                     [-cy * sp, -sy * sp, cp],
                     [cy * cp, sy * cp, sp]])


def focal_length_px(width: int, fov_deg: float) -> float:
    """Focal length in pixels for a HORIZONTAL field of view ``fov_deg``."""
    return (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)


def vertical_fov_deg(width: int, height: int, fov_deg: float) -> float:
    return math.degrees(2.0 * math.atan((height / 2.0) / focal_length_px(width, fov_deg)))


def pixel_rays_camera(width: int, height: int, fov_deg: float) -> np.ndarray:
    """(H, W, 3) camera-frame ray directions (right, up, forward) through the pixel centres.

    The forward component is 1, so the ray parameter of a hit IS its z-depth.
    """
    return _pixel_rays(width, height, focal_length_px(width, fov_deg))


def _pixel_rays(width: int, height: int, f: float) -> np.ndarray:
    x = (np.arange(width) + 0.5 - width / 2.0) / f
    y = (height / 2.0 - np.arange(height) - 0.5) / f
    out = np.empty((height, width, 3))
    out[..., 0] = x[None, :]
    out[..., 1] = y[:, None]
    out[..., 2] = 1.0
    return out


def project_points(points: np.ndarray, position, yaw: float, pitch: float, width: int = DEFAULT_WIDTH,
                   height: int = DEFAULT_HEIGHT, fov_deg: float = DEFAULT_FOV_DEG):
    """World points (N, 3) -> (col, row, z_depth) in pixel units (pixel centre of column j: j + 0.5)."""
    cam = (np.asarray(points, float) - np.asarray(position, float)) @ camera_axes(yaw, pitch).T
    f = focal_length_px(width, fov_deg)
    z = cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        col = width / 2.0 + f * cam[:, 0] / z
        row = height / 2.0 - f * cam[:, 1] / z
    return col, row, z


# ----------------------------------------------------------------------------------------------
# Mask feature
# ----------------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=16)
def _block_weights(n: int, blocks: int) -> np.ndarray:
    """(blocks, n) area-average weights: each row averages the pixels of one block (fractional
    pixels at block borders when ``n`` is not a multiple of ``blocks``)."""
    edges = np.arange(blocks + 1) * (n / blocks)
    lo = np.maximum(edges[:-1, None], np.arange(n)[None, :])
    hi = np.minimum(edges[1:, None], np.arange(n)[None, :] + 1)
    w = np.clip(hi - lo, 0.0, None) / (n / blocks)
    w.setflags(write=False)
    return w


@functools.lru_cache(maxsize=16)
def _feature_matrices(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """``rows (7, h)`` and ``cols (w, 7)`` so that ``rows @ mask @ cols`` holds the 5x5 block
    means (top-left), the sums of the normalised x and y pixel-centre coordinates and the count."""
    cols = np.zeros((w, 7))
    cols[:, :MASK_GRID] = _block_weights(w, MASK_GRID).T
    cols[:, 5] = 2.0 * (np.arange(w) + 0.5) / w - 1.0
    cols[:, 6] = 1.0
    rows = np.zeros((7, h))
    rows[:MASK_GRID] = _block_weights(h, MASK_GRID)
    rows[5] = 1.0 - 2.0 * (np.arange(h) + 0.5) / h
    rows[6] = 1.0
    cols.setflags(write=False)
    rows.setflags(write=False)
    return cols, rows


def mask_feature(mask: np.ndarray) -> np.ndarray:
    """Paper's mask feature plus a visibility flag: float32[30].

    ``[xc, yc, r, alpha, 25 x block mean of the 5x5 grid (row-major, top row first), visible]``.
    ``xc, yc`` are the mean pixel-centre coordinates of the set pixels normalised to [-1, 1] with
    the origin at the image centre, x to the right and y UP; ``r = hypot(xc, yc)``,
    ``alpha = atan2(yc, xc)``. The 30th entry (our addition) is 1.0 if any pixel is set. An
    empty mask gives all zeros.
    """
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim != 2:
        raise ValueError(f"mask must be 2-D, got shape {mask.shape}")
    out = np.zeros(MASK_FEATURE_DIM, np.float32)
    if not mask.any():
        return out
    h, w = mask.shape
    cols, rows = _feature_matrices(h, w)
    q = rows @ (mask.astype(np.float64) @ cols)  # (7, 7): block sums, coordinate sums, count
    n = q[6, 6]
    xc = float(q[6, 5] / n)
    yc = float(q[5, 6] / n)
    # Snap rounding noise so that a centred mask gets alpha = atan2(0, 0) = 0, not +-pi.
    xc = 0.0 if abs(xc) < 1e-9 else xc
    yc = 0.0 if abs(yc) < 1e-9 else yc
    out[0] = xc
    out[1] = yc
    out[2] = math.hypot(xc, yc)
    out[3] = math.atan2(yc, xc)
    out[4:4 + MASK_GRID * MASK_GRID] = q[:MASK_GRID, :MASK_GRID].ravel()
    out[-1] = 1.0
    return out


# ----------------------------------------------------------------------------------------------
# Geometry preparation
# ----------------------------------------------------------------------------------------------

class _Geometry:
    """Merged float32 vertices / int32 triangles with one group (vertex range, triangle range,
    bounding sphere) per part, for frustum culling."""

    def __init__(self, meshes):
        verts, tris, groups, spheres = [], [], [], []
        nv = nt = 0
        for mesh in meshes:
            v = np.asarray(mesh.vertices, np.float64)
            f = np.asarray(mesh.faces, np.int64)
            if len(f) == 0:
                continue
            lo, hi = v.min(axis=0), v.max(axis=0)
            centre = (lo + hi) / 2.0
            radius = float(np.sqrt(((v - centre) ** 2).sum(axis=1)).max()) * (1 + 1e-6) + 1e-6
            groups.append((nv, nv + len(v), nt, nt + len(f)))
            spheres.append((*centre, radius))
            verts.append(v)
            tris.append(f + nv)
            nv += len(v)
            nt += len(f)
        if nt:
            self.vertices = np.ascontiguousarray(np.concatenate(verts), np.float32)
            self.triangles = np.ascontiguousarray(np.concatenate(tris), np.int32)
        else:
            self.vertices = np.zeros((0, 3), np.float32)
            self.triangles = np.zeros((0, 3), np.int32)
        self.groups = np.ascontiguousarray(np.array(groups, np.int32).reshape(-1, 4))
        self.spheres = np.ascontiguousarray(np.array(spheres, np.float64).reshape(-1, 4))

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)

    def bbox_corners(self) -> np.ndarray:
        lo, hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                         for z in (lo[2], hi[2])], np.float64)


# ----------------------------------------------------------------------------------------------
# Backend 1: the C rasteriser
# ----------------------------------------------------------------------------------------------

#: The rasteriser's C source, shipped beside this module: built at install, or compiled on first use.
_RASTER_C = rasterbuild.SOURCE.read_text()


def _cache_dir() -> str:
    for candidate in (os.environ.get("EGOSEARCH_CACHE_DIR"),
                      os.path.join(os.path.expanduser("~"), ".cache", "egosearch"),
                      os.path.join(tempfile.gettempdir(), f"egosearch-{os.getuid()}")):
        if not candidate:
            continue
        try:
            os.makedirs(candidate, exist_ok=True)
            if os.access(candidate, os.W_OK):
                return candidate
        except OSError:
            continue
    raise OSError("no writable cache directory for the compiled rasteriser")


# one definition each, shared with the install's notice (egosearch.sim.rasterbuild)
_find_compiler = rasterbuild.find_compiler
_installed_library = rasterbuild.installed_library


def _build_of(lib) -> str:
    """What ``lib`` was built from and for (see :mod:`egosearch.sim.rasterbuild`)."""
    try:
        fn = lib.egosearch_raster_build
    except AttributeError:
        return "unknown"
    fn.argtypes, fn.restype = [], ctypes.c_char_p
    return fn().decode()


def _compile_into_cache() -> str:
    """Compile the rasteriser (once per machine, CPU and source, cached on disk) and return its
    path: the route when the install built none that fits. Raises without a C compiler."""
    flag_sets = rasterbuild.flag_sets(native=True)
    key = hashlib.sha1((_RASTER_C + repr(flag_sets) + rasterbuild.cpu_signature()).encode()).hexdigest()[:16]
    path = os.path.join(_cache_dir(), f"egosearch_raster_{key}.so")
    if os.path.exists(path):
        return path
    compiler = _find_compiler()
    if compiler is None:
        raise RuntimeError("no C compiler (cc/gcc/clang) found to build it on first use")
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "raster.c")
        with open(src, "w") as fh:
            fh.write(_RASTER_C)
        tmp_out = f"{path}.{os.getpid()}.tmp"
        errors = ""
        for flags in flag_sets:  # -march=native first (the file name carries the CPU signature), then portable
            proc = subprocess.run([compiler, "-fPIC", "-shared", *flags, "-o", tmp_out, src, "-lm"],
                                  capture_output=True, text=True, timeout=120)
            if proc.returncode == 0:
                break
            errors += proc.stderr
        else:
            raise RuntimeError(f"compiling it on first use failed: {errors.strip()[:2000]}")
        os.replace(tmp_out, path)  # atomic: parallel workers never load half a file
    return path


@functools.lru_cache(maxsize=1)
def _load_raster_library():
    """The C rasteriser: the library built at install when it fits this CPU and source, else one
    compiled on first use into a writable cache. Raises (saying why, for the sensor's one warning)
    when neither can be had; the sensor then falls back to Embree."""
    problems = []
    installed = _installed_library()
    if installed is None:
        problems.append("not built at install")
    else:
        lib = ctypes.CDLL(str(installed))
        why_not = rasterbuild.usable_here(_build_of(lib))
        if why_not is None:
            return _bind_render_frame(lib)
        problems.append(f"{installed.name} not used: {why_not}")
    try:
        return _bind_render_frame(ctypes.CDLL(_compile_into_cache()))
    except (OSError, RuntimeError, subprocess.SubprocessError) as err:
        raise RuntimeError("; ".join([*problems, str(err)])) from None


def _bind_render_frame(lib):
    fn = lib.render_frame
    vp, ci = ctypes.c_void_p, ctypes.c_int
    fn.argtypes = [vp, vp, vp, vp, ci, vp, vp, vp, vp, vp, ci, vp, vp, vp, vp, vp, ci, ci]
    fn.restype = ci
    return lib


class _RasterBackend:
    name = "raster"

    def __init__(self, geometry: _Geometry, width: int, height: int, f: float, max_depth: float):
        self._fn = _load_raster_library().render_frame
        self.width, self.height, self.f, self.max_depth = width, height, f, max_depth
        self._static_arrays, self._static = self._pack(geometry)
        self._target_arrays, self._target = None, (None, None, None, None, 0, None)
        self._cam = np.zeros(16, np.float64)
        self._cam[12:15] = (f, NEAR_PLANE, max_depth)
        self._izbuf = np.empty((height, width), np.float32)
        self._fixed = (self._cam.ctypes.data, self._izbuf.ctypes.data)

    @staticmethod
    def _pack(geometry: _Geometry):
        scratch = np.zeros((max(len(geometry.vertices), 1), 3), np.float64)
        arrays = (geometry.vertices, geometry.triangles, geometry.groups, geometry.spheres, scratch)
        return arrays, (arrays[0].ctypes.data, arrays[1].ctypes.data, arrays[2].ctypes.data,
                        arrays[3].ctypes.data, len(geometry.groups), arrays[4].ctypes.data)

    def set_target(self, geometry: _Geometry | None) -> None:
        if geometry is None or geometry.n_triangles == 0:
            self._target_arrays, self._target = None, (None, None, None, None, 0, None)
        else:
            self._target_arrays, self._target = self._pack(geometry)

    def render(self, position, axes: np.ndarray):
        cam = self._cam
        cam[0:3] = position
        cam[3:12] = axes.ravel()
        depth = np.empty((self.height, self.width), np.float32)
        mask = np.empty((self.height, self.width), np.bool_)
        self._fn(*self._static, *self._target, *self._fixed, depth.ctypes.data, mask.ctypes.data,
                 self.width, self.height)
        return depth, mask


# ----------------------------------------------------------------------------------------------
# Backend 2: Embree 4 ray packets through ctypes
# ----------------------------------------------------------------------------------------------

_RTC_GEOMETRY_TYPE_TRIANGLE = 0
_RTC_BUFFER_TYPE_INDEX = 0
_RTC_BUFFER_TYPE_VERTEX = 1
_RTC_FORMAT_UINT3 = 0x5003
_RTC_FORMAT_FLOAT3 = 0x9003
_RTC_BUILD_QUALITY_HIGH = 2
_RTC_INVALID_ID = 0xFFFFFFFF
# RTCRayHit16 in 32-bit words: ray (org xyz, tnear, dir xyz, time, tfar, mask, id, flags) x 16,
# hit (Ng xyz, u, v, primID, geomID, instID, instPrimID) x 16. 336 words = 21 cache lines.
_PK = 16
_PK_STRIDE = 21 * _PK
_OFF_ORG, _OFF_TNEAR, _OFF_DIR, _OFF_TFAR, _OFF_MASK, _OFF_GEOMID = 0, 48, 64, 128, 144, 288


@functools.lru_cache(maxsize=1)
def _load_embree_library():
    """Embree 4 as shipped inside the embreex wheel (or found on the system)."""
    candidates = []
    try:
        import embreex

        libs_dir = os.path.dirname(embreex.__file__) + ".libs"
        candidates += sorted(glob.glob(os.path.join(libs_dir, "libembree4*")))
        candidates += sorted(glob.glob(os.path.join(os.path.dirname(embreex.__file__), "libembree4*")))
    except ImportError:
        pass
    import ctypes.util

    found = ctypes.util.find_library("embree4")
    if found:
        candidates.append(found)
    errors = []
    for path in candidates:
        try:
            lib = ctypes.CDLL(path)
        except OSError as exc:
            errors.append(str(exc))
            continue
        vp, ci, cu, csz = ctypes.c_void_p, ctypes.c_int, ctypes.c_uint, ctypes.c_size_t
        sigs = {
            "rtcNewDevice": ([ctypes.c_char_p], vp),
            "rtcReleaseDevice": ([vp], None),
            "rtcGetDeviceError": ([vp], ci),
            "rtcNewScene": ([vp], vp),
            "rtcReleaseScene": ([vp], None),
            "rtcSetSceneBuildQuality": ([vp, ci], None),
            "rtcCommitScene": ([vp], None),
            "rtcNewGeometry": ([vp, ci], vp),
            "rtcSetNewGeometryBuffer": ([vp, ci, cu, ci, csz, csz], vp),
            "rtcCommitGeometry": ([vp], None),
            "rtcAttachGeometry": ([vp, vp], cu),
            "rtcReleaseGeometry": ([vp], None),
            "rtcIntersect16": ([vp, vp, vp, vp], None),
        }
        for name, (args, res) in sigs.items():
            fn = getattr(lib, name)
            fn.argtypes, fn.restype = args, res
        return lib
    raise RuntimeError(f"libembree4 not found (tried {candidates}; {errors})")


class _EmbreeBackend:
    name = "embree"

    def __init__(self, geometry: _Geometry, width: int, height: int, f: float, max_depth: float):
        self._lib = lib = _load_embree_library()
        self.width, self.height, self.f, self.max_depth = width, height, f, max_depth
        self._device = lib.rtcNewDevice(b"threads=1")
        if not self._device:
            raise RuntimeError("rtcNewDevice failed")
        self._scene = self._build(geometry)
        self._target_scene = None
        self._target_corners = None
        # 4x4 pixel tiles over the image padded to a multiple of 4.
        th, tw = -(-height // 4), -(-width // 4)
        self._tiles = th * tw
        tile_r, tile_c = np.divmod(np.arange(self._tiles), tw)
        rr, cc = np.divmod(np.arange(_PK), 4)
        rows = tile_r[:, None] * 4 + rr[None, :]
        cols = tile_c[:, None] * 4 + cc[None, :]
        self._tile_r0, self._tile_c0 = tile_r * 4, tile_c * 4
        rays = np.empty((self._tiles, 3, _PK))
        rays[:, 0, :] = (cols + 0.5 - width / 2.0) / f
        rays[:, 1, :] = (height / 2.0 - rows - 0.5) / f
        rays[:, 2, :] = 1.0
        self._rays = rays.astype(np.float32)
        keep = (rows < height) & (cols < width)
        self._gather = np.empty(height * width, np.int64)
        self._gather[(rows * width + cols)[keep]] = np.nonzero(keep.ravel())[0]
        raw = np.zeros(self._tiles * _PK_STRIDE + 16, np.float32)
        start = (-raw.ctypes.data % 64) // 4
        self._raw = raw
        self._buf = raw[start:start + self._tiles * _PK_STRIDE].reshape(self._tiles, _PK_STRIDE)
        self._buf.view(np.uint32)[:, _OFF_MASK:_OFF_MASK + _PK] = 0xFFFFFFFF
        # The ray parameter is the z-depth (forward component 1): tnear = the rasteriser's near plane.
        self._buf[:, _OFF_TNEAR:_OFF_TNEAR + _PK] = NEAR_PLANE
        self._dirs = self._buf[:, _OFF_DIR:_OFF_DIR + 3 * _PK].reshape(self._tiles, 3, _PK)
        self._orgs = self._buf[:, _OFF_ORG:_OFF_ORG + 3 * _PK].reshape(self._tiles, 3, _PK)
        self._tfar = self._buf[:, _OFF_TFAR:_OFF_TFAR + _PK]
        self._geomid = self._buf.view(np.uint32)[:, _OFF_GEOMID:_OFF_GEOMID + _PK]
        valid_raw = np.full(32, -1, np.int32)
        vstart = (-valid_raw.ctypes.data % 64) // 4
        self._valid_raw = valid_raw
        self._valid = ctypes.c_void_p(valid_raw[vstart:].ctypes.data)
        base = self._buf.ctypes.data
        self._packets = [ctypes.c_void_p(base + 4 * _PK_STRIDE * i) for i in range(self._tiles)]

    def _build(self, geometry: _Geometry):
        lib = self._lib
        scene = lib.rtcNewScene(self._device)
        lib.rtcSetSceneBuildQuality(scene, _RTC_BUILD_QUALITY_HIGH)
        if geometry.n_triangles:
            geom = lib.rtcNewGeometry(self._device, _RTC_GEOMETRY_TYPE_TRIANGLE)
            v = np.ascontiguousarray(geometry.vertices, np.float32)
            t = np.ascontiguousarray(geometry.triangles, np.uint32)
            vb = lib.rtcSetNewGeometryBuffer(geom, _RTC_BUFFER_TYPE_VERTEX, 0, _RTC_FORMAT_FLOAT3, 12, len(v))
            ctypes.memmove(vb, v.ctypes.data, v.nbytes)
            ib = lib.rtcSetNewGeometryBuffer(geom, _RTC_BUFFER_TYPE_INDEX, 0, _RTC_FORMAT_UINT3, 12, len(t))
            ctypes.memmove(ib, t.ctypes.data, t.nbytes)
            lib.rtcCommitGeometry(geom)
            lib.rtcAttachGeometry(scene, geom)
            lib.rtcReleaseGeometry(geom)
        lib.rtcCommitScene(scene)
        err = lib.rtcGetDeviceError(self._device)
        if err:
            raise RuntimeError(f"Embree error {err} while building a scene")
        return ctypes.c_void_p(scene)

    def set_target(self, geometry: _Geometry | None) -> None:
        if self._target_scene is not None:
            self._lib.rtcReleaseScene(self._target_scene)
            self._target_scene = None
        if geometry is not None and geometry.n_triangles:
            self._target_scene = self._build(geometry)
            self._target_corners = geometry.bbox_corners()

    def _target_tiles(self, position, axes):
        """Indices of the tiles that may see the target (its projected bounding box)."""
        cam = (self._target_corners - np.asarray(position, float)) @ axes.T
        z = cam[:, 2]
        if np.all(z <= NEAR_PLANE) or np.all(z > self.max_depth):
            return []
        if np.any(z <= NEAR_PLANE):
            return range(self._tiles)
        col = self.width / 2.0 + self.f * cam[:, 0] / z
        row = self.height / 2.0 - self.f * cam[:, 1] / z
        c0, c1, r0, r1 = col.min() - 1, col.max() + 1, row.min() - 1, row.max() + 1
        sel = ((self._tile_c0 + 4 > c0) & (self._tile_c0 < c1)
               & (self._tile_r0 + 4 > r0) & (self._tile_r0 < r1))
        return np.nonzero(sel)[0].tolist()

    def render(self, position, axes: np.ndarray):
        np.matmul(axes.T.astype(np.float32), self._rays, out=self._dirs)
        self._orgs[...] = np.asarray(position, np.float32)[None, :, None]
        self._tfar[...] = self.max_depth
        isect, valid, scene = self._lib.rtcIntersect16, self._valid, self._scene
        for packet in self._packets:
            isect(valid, scene, packet, None)
        mask_flat = None
        if self._target_scene is not None:
            tiles = self._target_tiles(position, axes)
            if len(tiles):
                self._geomid[...] = _RTC_INVALID_ID
                tscene, packets = self._target_scene, self._packets
                for i in tiles:
                    isect(valid, tscene, packets[i], None)
                mask_flat = (self._geomid != _RTC_INVALID_ID).ravel()[self._gather]
        depth = self._tfar.ravel()[self._gather].reshape(self.height, self.width)
        if mask_flat is None:
            mask = np.zeros((self.height, self.width), np.bool_)
        else:
            mask = mask_flat.reshape(self.height, self.width)
        return np.minimum(depth, np.float32(self.max_depth)), mask

    def __del__(self):
        lib = getattr(self, "_lib", None)
        if lib is None:
            return
        try:
            if getattr(self, "_target_scene", None) is not None:
                lib.rtcReleaseScene(self._target_scene)
            if getattr(self, "_scene", None) is not None:
                lib.rtcReleaseScene(self._scene)
            if getattr(self, "_device", None):
                lib.rtcReleaseDevice(self._device)
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass


# ----------------------------------------------------------------------------------------------
# Backend 3: embreex's per-ray API
# ----------------------------------------------------------------------------------------------

class _EmbreexBackend:
    name = "embreex"

    def __init__(self, geometry: _Geometry, width: int, height: int, f: float, max_depth: float):
        from embreex import rtcore_scene  # noqa: F401 - fail early if missing

        self.width, self.height, self.f, self.max_depth = width, height, f, max_depth
        self._scene = self._build(geometry)
        self._target = None
        self._rays = _pixel_rays(width, height, f).reshape(-1, 3).astype(np.float32)

    @staticmethod
    def _build(geometry: _Geometry):
        from embreex import mesh_construction, rtcore_scene

        scene = rtcore_scene.EmbreeScene()
        if geometry.n_triangles:
            mesh_construction.TriangleMesh(scene, geometry.vertices.astype(np.float32),
                                           geometry.triangles.astype(np.int32))
        return scene

    def set_target(self, geometry: _Geometry | None) -> None:
        self._target = None if geometry is None or geometry.n_triangles == 0 else self._build(geometry)

    def render(self, position, axes: np.ndarray):
        dirs = np.ascontiguousarray(self._rays @ axes.astype(np.float32))
        orgs = np.ascontiguousarray(np.broadcast_to(np.asarray(position, np.float32), dirs.shape))
        tfar = np.full(len(dirs), self.max_depth, np.float32)
        depth = self._scene.run(orgs, dirs, dists=tfar, query="DISTANCE")
        mask = np.zeros(len(dirs), np.bool_)
        if self._target is not None:
            tdepth = self._target.run(orgs, dirs, dists=depth.copy(), query="DISTANCE")
            mask = tdepth < depth
            depth = np.minimum(depth, tdepth)
        depth = np.minimum(depth, np.float32(self.max_depth))
        return depth.reshape(self.height, self.width), mask.reshape(self.height, self.width)


_BACKEND_CLASSES = {"raster": _RasterBackend, "embree": _EmbreeBackend, "embreex": _EmbreexBackend}


# ----------------------------------------------------------------------------------------------
# The sensor
# ----------------------------------------------------------------------------------------------

class DepthMaskSensor:
    """Depth + target mask camera over a static :class:`Scene` (see the module docstring).

    ``fov_deg`` is the horizontal field of view; pixels are square. The static house is prepared
    once; :meth:`set_target` (once per episode) only prepares the small target mesh. ``backend``:
    ``"auto"`` (the fastest that loads, with a warning when it is not the rasteriser) or one of
    :data:`BACKENDS`. Instances pickle (they are rebuilt on unpickling).
    """

    def __init__(self, scene: Scene, width: int = DEFAULT_WIDTH, height: int = DEFAULT_HEIGHT,
                 fov_deg: float = DEFAULT_FOV_DEG, max_depth: float = DEFAULT_MAX_DEPTH,
                 backend: str = "auto"):
        if width < 1 or height < 1:
            raise ValueError("width and height must be positive")
        if not 0 < fov_deg < 180:
            raise ValueError("fov_deg must be in (0, 180)")
        self.scene = scene
        self.width, self.height = int(width), int(height)
        self.fov_deg = float(fov_deg)
        self.max_depth = float(max_depth)
        self.focal_px = focal_length_px(self.width, self.fov_deg)
        self._geometry = _Geometry([mesh for _, mesh in scene_meshes(scene)])
        self.target: Part | None = None
        self._requested_backend = backend
        order = BACKENDS if backend == "auto" else (backend,)
        if backend != "auto" and backend not in BACKENDS:
            raise ValueError(f"backend={backend!r}; allowed: auto, {', '.join(BACKENDS)}")
        errors = []
        self._backend = None
        for name in order:
            try:
                self._backend = _BACKEND_CLASSES[name](self._geometry, self.width, self.height,
                                                       self.focal_px, self.max_depth)
                break
            except Exception as exc:  # noqa: BLE001 - fall back to the next backend
                errors.append(f"{name}: {exc}")
                if backend != "auto":
                    raise
        if self._backend is None:
            raise RuntimeError("no sensor backend could be loaded: " + "; ".join(errors))
        if errors:
            warnings.warn("DepthMaskSensor fell back to the " f"{self._backend.name!r} backend ("
                          + "; ".join(errors) + ")", RuntimeWarning, stacklevel=2)

    def __reduce__(self):
        # Compiled handles do not pickle: rebuild from the description (e.g. in a worker process).
        return (_rebuild_sensor, (self.scene, self.width, self.height, self.fov_deg, self.max_depth,
                                  self._requested_backend, self.target))

    @property
    def backend(self) -> str:
        """The backend in use: one of :data:`BACKENDS`."""
        return self._backend.name

    @property
    def n_triangles(self) -> int:
        return self._geometry.n_triangles

    def set_target(self, part: Part | None) -> None:
        """The object whose pixels form the mask (None: no target, empty masks)."""
        self.target = part
        self._backend.set_target(None if part is None else _Geometry([part_mesh(part)]))

    def render(self, position, yaw: float, pitch: float) -> tuple[np.ndarray, np.ndarray]:
        """(depth float32[H, W] in metres, mask bool[H, W]) from ``position`` looking (yaw, pitch)."""
        return self._backend.render(position, camera_axes(yaw, pitch))

    def render_uint8(self, position, yaw: float, pitch: float) -> tuple[np.ndarray, np.ndarray]:
        """Depth as uint8 ``round(255 * depth / max_depth)`` and the mask."""
        depth, mask = self.render(position, yaw, pitch)
        return depth_to_uint8(depth, self.max_depth), mask


def _rebuild_sensor(scene, width, height, fov_deg, max_depth, backend, target) -> DepthMaskSensor:
    sensor = DepthMaskSensor(scene, width, height, fov_deg, max_depth, backend)
    sensor.set_target(target)
    return sensor


def depth_to_uint8(depth: np.ndarray, max_depth: float = DEFAULT_MAX_DEPTH) -> np.ndarray:
    scaled = np.rint(np.clip(depth, 0.0, max_depth) * (255.0 / max_depth))
    return scaled.astype(np.uint8)


# ----------------------------------------------------------------------------------------------
# Benchmark
# ----------------------------------------------------------------------------------------------

def random_poses(scene: Scene, n: int, seed: int = 0):
    """Random camera poses inside the scene bounds: heights 0.45-1.8 m, any yaw, pitch in [-0.8, 0.5]."""
    rng = np.random.default_rng(seed)
    x0, y0, x1, y1 = scene.bounds
    xs = rng.uniform(x0, x1, n)
    ys = rng.uniform(y0, y1, n)
    zs = rng.uniform(0.45, 1.8, n)
    yaws = rng.uniform(-math.pi, math.pi, n)
    pitches = rng.uniform(-0.8, 0.5, n)
    return [((float(x), float(y), float(z)), float(a), float(p))
            for x, y, z, a, p in zip(xs, ys, zs, yaws, pitches)]


def _benchmark_target(scene: Scene, rng) -> Part:
    if scene.surfaces:
        s = scene.surfaces[int(rng.integers(len(scene.surfaces)))]
        centre = (s.center[0], s.center[1], s.center[2] + 0.06)
    else:
        x0, y0, x1, y1 = scene.bounds
        centre = ((x0 + x1) / 2, (y0 + y1) / 2, 0.8)
    return Part("bench/target", "box", centre, (0.12, 0.12, 0.12), tags={"target"})


def bench_sensor(scene: Scene, n_frames: int = 2000, seed: int = 0, width: int = DEFAULT_WIDTH,
                 height: int = DEFAULT_HEIGHT, backend: str = "auto") -> dict:
    """Frames per second of :meth:`DepthMaskSensor.render` (depth + mask, a target set) over
    random poses. Run under ``taskset -c 0`` to measure one core."""
    t0 = time.perf_counter()
    sensor = DepthMaskSensor(scene, width=width, height=height, backend=backend)
    sensor.set_target(_benchmark_target(scene, np.random.default_rng(seed)))
    build_s = time.perf_counter() - t0
    poses = random_poses(scene, n_frames, seed)
    for pose in poses[: min(50, n_frames)]:
        sensor.render(*pose)
    visible = 0
    t0, c0 = time.perf_counter(), time.process_time()
    for pose in poses:
        _, mask = sensor.render(*pose)
        visible += bool(mask.any())
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    return {
        "sensor_frames_per_s": n_frames / elapsed,
        "sensor_ms_per_frame": 1e3 * elapsed / n_frames,
        # CPU time of this process: less sensitive to other processes sharing the core.
        "sensor_cpu_ms_per_frame": 1e3 * cpu / n_frames,
        "triangles": sensor.n_triangles,
        "backend": sensor.backend,
        "width": width,
        "height": height,
        "n_frames": n_frames,
        "build_s": build_s,
        "frames_with_target_visible": visible,
    }
