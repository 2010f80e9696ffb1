"""The world: Safe-ROS's reactor-room occupancy map, unmapped obstacles, LiDAR ray casting and
ground-truth clearance.

Frames and units follow REP 103: the ``map`` frame is x forward/east, y left/north, z up,
distances in metres, angles in radians counter-clockwise.

Two views of the same room exist on purpose:

* the **static map** (:class:`OccupancyMap`): what ``map_server`` serves on ``/map`` and what the
  navigation stack plans on. It is the Safe-ROS map unchanged.
* the **physical world** (:class:`World`): what the LiDAR sees and what the robot can hit. It is
  the static map minus objects that were moved away (:attr:`World.removed`), plus unmapped round
  objects (:class:`Barrel`) and objects that move (:class:`MovingObstacle`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml
from PIL import Image
from scipy import ndimage

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

#: Folder holding the shipped copy of the Safe-ROS map (BSD-3-Clause, see ``data/NOTICE``).
DATA_DIR = Path(__file__).resolve().parent / "data"
#: The reactor-room map's YAML (map_server format).
REACTOR_ROOM_YAML = DATA_DIR / "reactor_room_map.yaml"

#: nav_msgs/OccupancyGrid cell values (ROS message definition: 0 free, 100 occupied, -1 unknown).
FREE, OCCUPIED, UNKNOWN = 0, 100, -1


class OccupancyMap:
    """A ``map_server`` map: a trinary occupancy grid in the ``map`` frame.

    ``grid`` has shape ``(height, width)``, dtype int8, values ``0`` (free), ``100``
    (occupied), ``-1`` (unknown); row 0 is the row of cells at ``y = origin_y`` (the bottom of
    the image), i.e. exactly the row-major order of ``nav_msgs/OccupancyGrid.data``.
    Cell ``(row, col)`` covers ``[origin_x + col*res, origin_x + (col+1)*res)`` in x and the
    same in y with ``row``.

    The thresholding follows ``map_server``'s trinary mode (ROS map_server documentation):
    ``p = (255 - pixel) / 255`` (``negate: 0``); ``p > occupied_thresh`` is occupied,
    ``p < free_thresh`` free, anything else unknown.
    """

    def __init__(self, image: np.ndarray, resolution: float, origin: Sequence[float],
                 negate: int = 0, occupied_thresh: float = 0.65, free_thresh: float = 0.196):
        """``image``: uint8 array ``(height, width)`` with the top image row first (PGM order);
        ``resolution`` in m/cell; ``origin`` = (x, y, yaw) of the lower-left cell corner in m, rad.

        Raises ``ValueError`` for a non-2-D image, a non-positive resolution or a rotated
        origin (map_server ignores yaw in practice; we refuse it rather than misplace cells).
        """
        image = np.asarray(image)
        if image.ndim != 2:
            raise ValueError(f"map image must be 2-D, got shape {image.shape}")
        if not resolution > 0:
            raise ValueError(f"map resolution must be > 0, got {resolution}")
        if len(origin) >= 3 and float(origin[2]) != 0.0:
            raise ValueError("rotated map origins are not supported")
        self.resolution = float(resolution)
        self.origin_x = float(origin[0])
        self.origin_y = float(origin[1])
        self.height, self.width = image.shape
        pix = image[::-1].astype(np.float64)  # row 0 = bottom
        p = pix / 255.0 if negate else (255.0 - pix) / 255.0
        grid = np.full(image.shape, UNKNOWN, dtype=np.int8)
        grid[p > occupied_thresh] = OCCUPIED
        grid[p < free_thresh] = FREE
        self.grid = grid

    @classmethod
    def load(cls, yaml_path: str | Path = REACTOR_ROOM_YAML) -> OccupancyMap:
        """Read a map_server YAML and the image it names (PGM, via Pillow).

        Raises ``FileNotFoundError`` if either file is missing and ``KeyError`` if the YAML
        lacks ``image``, ``resolution`` or ``origin``.
        """
        yaml_path = Path(yaml_path)
        meta = yaml.safe_load(yaml_path.read_text())
        image = np.array(Image.open(yaml_path.parent / meta["image"]).convert("L"))
        return cls(image, meta["resolution"], meta["origin"], int(meta.get("negate", 0)),
                   float(meta.get("occupied_thresh", 0.65)), float(meta.get("free_thresh", 0.196)))

    # ------------------------------------------------------------------ coordinates
    def cell_of(self, x: ArrayLike, y: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Cell indices ``(row, col)`` (int arrays, same shape as ``x``/``y``) containing the
        points ``(x, y)`` in m; indices may fall outside the grid (check :meth:`inside`)."""
        col = np.floor((np.asarray(x) - self.origin_x) / self.resolution).astype(np.int64)
        row = np.floor((np.asarray(y) - self.origin_y) / self.resolution).astype(np.int64)
        return row, col

    def inside(self, row: np.ndarray, col: np.ndarray) -> np.ndarray:
        """Boolean mask: which ``(row, col)`` lie inside the grid."""
        return (row >= 0) & (row < self.height) & (col >= 0) & (col < self.width)

    def cell_centers(self, row: ArrayLike, col: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Centres ``(x, y)`` in m of cells ``(row, col)``."""
        return (self.origin_x + (np.asarray(col) + 0.5) * self.resolution,
                self.origin_y + (np.asarray(row) + 0.5) * self.resolution)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` of the grid in m (for matplotlib's ``imshow``)."""
        return (self.origin_x, self.origin_x + self.width * self.resolution,
                self.origin_y, self.origin_y + self.height * self.resolution)

    def obstacle_mask(self, unknown_is_obstacle: bool = True) -> np.ndarray:
        """Bool ``(height, width)``: occupied cells, and unknown ones if asked (the unknown
        cells of this map are the insides of walls, tanks and drums)."""
        mask = self.grid == OCCUPIED
        if unknown_is_obstacle:
            mask |= self.grid == UNKNOWN
        return mask


# ---------------------------------------------------------------------- unmapped obstacles
@dataclass(frozen=True)
class Barrel:
    """A static round object (drum, barrel) at ``(x, y)`` m with ``radius`` m, absent from the
    static map."""

    x: float
    y: float
    radius: float
    label: str = "barrel"


@dataclass(frozen=True)
class MovingObstacle:
    """A round object (a person, a trolley) of ``radius`` m walking the polyline ``waypoints``
    ((x, y) in m) at constant ``speed`` m/s, starting at sim time ``t_start`` s; it waits at the
    first waypoint before and at the last one after its walk."""

    waypoints: tuple[tuple[float, float], ...]
    speed: float
    radius: float
    t_start: float
    label: str = "person"

    def __post_init__(self):
        if len(self.waypoints) < 2:
            raise ValueError("a MovingObstacle needs at least two waypoints")
        if not self.speed > 0:
            raise ValueError("MovingObstacle.speed must be > 0")

    def position(self, t: float) -> tuple[float, float]:
        """Position (x, y) in m at sim time ``t`` s."""
        pts = np.asarray(self.waypoints, dtype=float)
        seg = np.hypot(*np.diff(pts, axis=0).T)
        s = min(max(t - self.t_start, 0.0) * self.speed, float(seg.sum()))
        for i, length in enumerate(seg):
            if s <= length or i == len(seg) - 1:
                a = s / length if length > 0 else 0.0
                a = min(a, 1.0)
                return (float(pts[i, 0] + a * (pts[i + 1, 0] - pts[i, 0])),
                        float(pts[i, 1] + a * (pts[i + 1, 1] - pts[i, 1])))
            s -= length
        return float(pts[-1, 0]), float(pts[-1, 1])  # pragma: no cover


@dataclass(frozen=True)
class RemovedObject:
    """A mapped round object that is no longer there (it was moved): every solid cell whose
    centre lies within ``radius`` m of ``(x, y)`` is cleared from the physical world."""

    x: float
    y: float
    radius: float
    label: str = "moved away"


# ---------------------------------------------------------------------- physical world
_SQRT2 = math.sqrt(2.0)


@dataclass
class World:
    """The physical room: static map minus :attr:`removed`, plus :attr:`barrels` and
    :attr:`movers`. Solid cells are the map's occupied *and* unknown cells (the unknown cells
    are the insides of objects), each an axis-aligned square of side ``resolution``."""

    omap: OccupancyMap
    barrels: tuple[Barrel, ...] = ()
    movers: tuple[MovingObstacle, ...] = ()
    removed: tuple[RemovedObject, ...] = ()
    solid: np.ndarray = field(init=False, repr=False)
    edt: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        m = self.omap
        solid = m.obstacle_mask(unknown_is_obstacle=True)
        if self.removed:
            rows, cols = np.nonzero(solid)
            cx, cy = m.cell_centers(rows, cols)
            gone = np.zeros(rows.shape, bool)
            for r in self.removed:
                gone |= np.hypot(cx - r.x, cy - r.y) <= r.radius
            solid[rows[gone], cols[gone]] = False
        self.solid = solid
        cross = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], bool)
        boundary = solid & ~ndimage.binary_erosion(solid, structure=cross, border_value=0)
        br, bc = np.nonzero(boundary)
        self._bx, self._by = m.cell_centers(br, bc)
        # Distance (m) from each cell centre to the nearest solid cell centre.
        self.edt = ndimage.distance_transform_edt(~solid) * m.resolution

    # ------------------------------------------------------------------ circles
    def circles(self, t: float) -> np.ndarray:
        """Round objects at sim time ``t`` s: float array ``(n, 3)`` of ``(x, y, radius)`` m."""
        rows = [(b.x, b.y, b.radius) for b in self.barrels]
        rows += [(*mv.position(t), mv.radius) for mv in self.movers]
        return np.array(rows, dtype=float).reshape(-1, 3)

    # ------------------------------------------------------------------ ray casting
    def raycast(self, x: float, y: float, angles: np.ndarray, t: float,
                max_range: float) -> np.ndarray:
        """True range (m) from ``(x, y)`` along each world-frame direction in ``angles``
        (rad, shape ``(n,)``) to the first solid cell or round object at sim time ``t``;
        ``inf`` where nothing is hit within ``max_range`` m. Returns float64 ``(n,)``.

        The rays must be equally spaced, as in a ``LaserScan``. Map part: exact intersection
        with the solid cell squares (see :meth:`_raycast_map`); round objects: exact
        ray-circle intersection. Vectorized over rays and cells.
        """
        angles = np.asarray(angles, dtype=float)
        dx, dy = np.cos(angles), np.sin(angles)
        ranges = self._raycast_map(x, y, dx, dy, max_range)
        circ = self.circles(t)
        if len(circ):
            fx = x - circ[:, 0][:, None]
            fy = y - circ[:, 1][:, None]
            b = fx * dx[None, :] + fy * dy[None, :]
            c = (fx * fx + fy * fy - circ[:, 2][:, None] ** 2)
            c = np.broadcast_to(c, b.shape)
            disc = b * b - c
            with np.errstate(invalid="ignore"):
                t1 = -b - np.sqrt(disc)
            hit = (disc >= 0) & (t1 >= 0)
            tc = np.where(hit, t1, np.inf)
            tc = np.where(c < 0, 0.0, tc)  # the lidar is inside the object
            ranges = np.minimum(ranges, tc.min(axis=0))
        ranges[ranges > max_range] = np.inf
        return ranges

    def _raycast_map(self, x, y, dx, dy, max_range):
        """Exact first hit of each ray with the boundary cells (solid cells with a free
        4-neighbour: a ray from free space enters the solid through one of them). Every
        boundary square is projected to the interval of ray angles it subtends; each
        (square, ray) pair inside that interval is intersected exactly (slab method) and
        the nearest hit per ray is kept."""
        bx, by = self._bx, self._by
        e = self.omap.resolution / 2.0
        n = dx.shape[0]
        ang = np.arctan2(dy, dx)
        # rays must be equally spaced (a LaserScan); find the spacing and the first angle
        inc = float(np.arctan2(dx[0] * dy[1] - dy[0] * dx[1], dx[0] * dx[1] + dy[0] * dy[1])) \
            if n > 1 else 1.0
        a0 = float(ang[0])
        full = n > 1 and abs(n * inc - 2 * math.pi) < 1e-9
        relx, rely = bx - x, by - y
        phi_c = np.arctan2(rely, relx)
        lo = np.full(bx.shape, np.inf)
        hi = np.full(bx.shape, -np.inf)
        for ox in (-e, e):
            for oy in (-e, e):
                d = np.arctan2(rely + oy, relx + ox) - phi_c
                d = (d + math.pi) % (2 * math.pi) - math.pi
                lo = np.minimum(lo, d)
                hi = np.maximum(hi, d)
        inside = (np.abs(relx) <= e) & (np.abs(rely) <= e)
        lo = np.where(inside, -math.pi, lo)
        hi = np.where(inside, math.pi, hi)
        k_lo = np.ceil((phi_c + lo - a0) / inc - 1e-9).astype(np.int64)
        k_hi = np.floor((phi_c + hi - a0) / inc + 1e-9).astype(np.int64)
        if not full:  # a partial fan: rays outside [0, n) do not exist
            # bring each interval into the window nearest to [0, n)
            shift = np.round(((k_lo + k_hi) / 2.0 - (n - 1) / 2.0) * inc / (2 * math.pi))
            per = 2 * math.pi / inc
            k_lo = k_lo - np.round(shift * per).astype(np.int64)
            k_hi = k_hi - np.round(shift * per).astype(np.int64)
            k_lo = np.maximum(k_lo, 0)
            k_hi = np.minimum(k_hi, n - 1)
        cnt = np.maximum(k_hi - k_lo + 1, 0)
        cnt = np.minimum(cnt, n)
        total = int(cnt.sum())
        out = np.full(n, np.inf)
        if total == 0:
            return out
        cell = np.repeat(np.arange(bx.size), cnt)
        start = np.repeat(np.cumsum(cnt) - cnt, cnt)
        ray = (np.repeat(k_lo, cnt) + (np.arange(total) - start)) % n
        rx, ry = dx[ray], dy[ray]
        cx, cy = relx[cell], rely[cell]
        with np.errstate(divide="ignore", invalid="ignore"):
            t1x, t2x = (cx - e) / rx, (cx + e) / rx
            t1y, t2y = (cy - e) / ry, (cy + e) / ry
        # rays parallel to an axis: the slab is all or nothing
        zx, zy = rx == 0, ry == 0
        inx = np.abs(cx) <= e
        iny = np.abs(cy) <= e
        tnx = np.where(zx, np.where(inx, -np.inf, np.inf), np.minimum(t1x, t2x))
        tfx = np.where(zx, np.where(inx, np.inf, -np.inf), np.maximum(t1x, t2x))
        tny = np.where(zy, np.where(iny, -np.inf, np.inf), np.minimum(t1y, t2y))
        tfy = np.where(zy, np.where(iny, np.inf, -np.inf), np.maximum(t1y, t2y))
        tn = np.maximum(tnx, tny)
        tf = np.minimum(tfx, tfy)
        ok = (tn <= tf) & (tf >= 0)
        tt = np.where(ok, np.maximum(tn, 0.0), np.inf)
        np.minimum.at(out, ray, tt)
        out[out > max_range] = np.inf
        return out

    # ------------------------------------------------------------------ clearance
    def clearance(self, x: float, y: float, yaw: float, t: float,
                  half_length: float, half_width: float) -> float:
        """Ground-truth clearance (m): the Euclidean distance from the robot's footprint
        rectangle (centre ``(x, y)`` m, heading ``yaw`` rad, half extents along/across the
        heading in m) to the nearest solid cell square or round object at sim time ``t``.
        ``0`` when the footprint touches a solid cell; negative when it overlaps a round
        object (minus the depth of the overlap)."""
        best = self._clearance_map(x, y, yaw, half_length, half_width)
        circ = self.circles(t)
        if len(circ):
            best = min(best, float(np.min(
                _point_rect_distance(circ[:, 0], circ[:, 1], x, y, yaw, half_length,
                                     half_width, signed=True) - circ[:, 2])))
        return best

    def clearance_lower_bound(self, x: float, y: float, t: float, radius: float) -> float:
        """A cheap lower bound (m) on :meth:`clearance` for any footprint within ``radius`` m
        of ``(x, y)`` (use the footprint's circumradius)."""
        m = self.omap
        r, c = m.cell_of(x, y)
        if not m.inside(r, c):
            lb = math.inf
        else:
            lb = float(self.edt[r, c]) - m.resolution * _SQRT2 - radius
        circ = self.circles(t)
        if len(circ):
            lb = min(lb, float(np.min(np.hypot(circ[:, 0] - x, circ[:, 1] - y) - circ[:, 2]))
                     - radius)
        return lb

    def _clearance_map(self, x, y, yaw, hl, hw):
        m = self.omap
        res = m.resolution
        r0, c0 = m.cell_of(x, y)
        if not m.inside(r0, c0):
            return math.inf
        # The nearest solid square is within (edt + slack + circumradius) of the centre.
        reach = float(self.edt[r0, c0]) + res * 2 + math.hypot(hl, hw)
        n = int(math.ceil(reach / res)) + 1
        rs, re = max(int(r0) - n, 0), min(int(r0) + n + 1, m.height)
        cs, ce = max(int(c0) - n, 0), min(int(c0) + n + 1, m.width)
        rows, cols = np.nonzero(self.solid[rs:re, cs:ce])
        if rows.size == 0:
            return math.inf
        sx, sy = m.cell_centers(rows + rs, cols + cs)
        e = res / 2.0
        # (a) rectangle corners to each square
        cy_, sy_ = math.cos(yaw), math.sin(yaw)
        corners = [(sgx * hl, sgy * hw) for sgx in (-1, 1) for sgy in (-1, 1)]
        best = np.full(sx.shape, np.inf)
        for (u, v) in corners:
            vx = x + u * cy_ - v * sy_
            vy = y + u * sy_ + v * cy_
            ddx = np.maximum(np.abs(vx - sx) - e, 0.0)
            ddy = np.maximum(np.abs(vy - sy) - e, 0.0)
            best = np.minimum(best, np.hypot(ddx, ddy))
        # (b) square corners to the rectangle
        for ox in (-e, e):
            for oy in (-e, e):
                best = np.minimum(best, _point_rect_distance(sx + ox, sy + oy, x, y, yaw,
                                                             hl, hw))
        return float(best.min())


def _point_rect_distance(px, py, x, y, yaw, hl, hw, signed=False):
    """Distance (m) from points ``(px, py)`` (arrays) to the rectangle centred at ``(x, y)``
    with heading ``yaw`` and half extents ``hl`` (along), ``hw`` (across); with ``signed``,
    points inside get minus their distance to the boundary."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = np.asarray(px) - x, np.asarray(py) - y
    u = np.abs(dx * c + dy * s) - hl
    v = np.abs(-dx * s + dy * c) - hw
    outside = np.hypot(np.maximum(u, 0.0), np.maximum(v, 0.0))
    if not signed:
        return outside
    return np.where((u < 0) & (v < 0), np.maximum(u, v), outside)
