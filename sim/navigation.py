"""The Safety-Related Autonomous System (SRAS): a move_base-like navigation stack.

Design notes: ARCHITECTURE.md, `sim/navigation.py`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from fretc.sim.robot import wrap_angle
from fretc.sim.world import OccupancyMap


@dataclass(frozen=True)
class PlannerParams:
    """Global planner settings: ``inflation_radius`` m (cells whose centre is closer than this
    to an obstacle cell are lethal for the robot centre), soft cost ``cost_weight *
    exp(-(d - inflation_radius) / cost_length)`` for clearance ``d`` m (added per metre of
    path), ``unknown_is_obstacle`` (navfn ``allow_unknown: false``)."""

    inflation_radius: float = 0.30
    cost_weight: float = 6.0
    cost_length: float = 0.4
    unknown_is_obstacle: bool = True


class NavigationFunction:
    """Cost-to-go towards one goal over the planner's grid (made by :meth:`GlobalPlanner.plan`):
    ``dist`` (float, one per traversable cell) and ``pred`` (next cell towards the goal, -1 at
    the goal or where unreachable)."""

    def __init__(self, planner: GlobalPlanner, goal: tuple[float, float],
                 dist: np.ndarray, pred: np.ndarray):
        self.planner = planner
        self.goal = goal
        self.dist = dist
        self.pred = pred

    def cost_to_go(self, x: float, y: float) -> float:
        """Weighted path length (m-equivalent) from ``(x, y)`` to the goal; ``inf`` if the
        point is not on a traversable cell connected to the goal."""
        node = self.planner.node_of(x, y)
        return math.inf if node < 0 else float(self.dist[node])

    def path_from(self, x: float, y: float, max_length: float = 3.0) -> np.ndarray:
        """Grid path (cell centres, float ``(k, 2)`` in m) from ``(x, y)`` towards the goal,
        at most ``max_length`` m long, ending at the goal itself when it is reached. If
        ``(x, y)`` is off the traversable grid (e.g. inside the inflation), starts from the
        nearest traversable cell within 1 m; returns an empty array if there is none."""
        pl = self.planner
        node = pl.node_of(x, y)
        if node < 0 or not math.isfinite(self.dist[node]):
            node = pl.nearest_node(x, y, self.dist, 1.0)
            if node < 0:
                return np.zeros((0, 2))
        pts = [pl.node_xy(node)]
        length = 0.0
        while length < max_length:
            nxt = self.pred[node]
            if nxt < 0:
                break
            p = pl.node_xy(nxt)
            length += math.hypot(p[0] - pts[-1][0], p[1] - pts[-1][1])
            pts.append(p)
            node = nxt
        if self.pred[node] < 0:  # reached the goal cell: end exactly at the goal
            pts.append(self.goal)
        return np.array(pts, dtype=float)


class GlobalPlanner:
    """navfn-like planner on the inflated static map (see module docstring)."""

    def __init__(self, omap: OccupancyMap, params: PlannerParams = PlannerParams()):
        """Builds the costmap and the grid graph once (the static map never changes)."""
        self.omap = omap
        self.params = params
        obst = omap.obstacle_mask(params.unknown_is_obstacle)
        d = ndimage.distance_transform_edt(~obst) * omap.resolution
        self.clearance = d
        free = d >= params.inflation_radius
        cost = params.cost_weight * np.exp(-(d - params.inflation_radius) / params.cost_length)
        self.traversable = free
        H, W = free.shape
        ids = -np.ones((H, W), dtype=np.int64)
        rows, cols = np.nonzero(free)
        ids[rows, cols] = np.arange(rows.size)
        self.ids = ids
        self.rows, self.cols = rows, cols
        src_parts: list[np.ndarray] = []
        dst_parts: list[np.ndarray] = []
        wts_parts: list[np.ndarray] = []
        res = omap.resolution
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            r2, c2 = rows + dr, cols + dc
            ok = (r2 >= 0) & (r2 < H) & (c2 >= 0) & (c2 < W)
            ok[ok] &= free[r2[ok], c2[ok]]
            a = ids[rows[ok], cols[ok]]
            b = ids[r2[ok], c2[ok]]
            step = res * math.hypot(dr, dc)
            w = step * (1.0 + 0.5 * (cost[rows[ok], cols[ok]] + cost[r2[ok], c2[ok]]))
            src_parts.append(a)
            dst_parts.append(b)
            wts_parts.append(w)
        src = np.concatenate(src_parts)
        dst = np.concatenate(dst_parts)
        wts = np.concatenate(wts_parts)
        n = rows.size
        self.graph = csr_matrix((np.concatenate([wts, wts]),
                                 (np.concatenate([src, dst]), np.concatenate([dst, src]))),
                                shape=(n, n))

    def node_of(self, x: float, y: float) -> int:
        """Graph node of the cell containing ``(x, y)``, or -1 if not traversable."""
        r, c = self.omap.cell_of(x, y)
        if not self.omap.inside(r, c):
            return -1
        return int(self.ids[r, c])

    def node_xy(self, node: int) -> tuple[float, float]:
        """Centre (x, y) in m of a node's cell."""
        x, y = self.omap.cell_centers(self.rows[node], self.cols[node])
        return float(x), float(y)

    def nearest_node(self, x: float, y: float, dist: np.ndarray, radius: float) -> int:
        """Nearest traversable node within ``radius`` m with finite ``dist``, or -1."""
        m = self.omap
        r0, c0 = m.cell_of(x, y)
        n = int(math.ceil(radius / m.resolution))
        best, best_d = -1, math.inf
        for r in range(int(r0) - n, int(r0) + n + 1):
            for c in range(int(c0) - n, int(c0) + n + 1):
                if 0 <= r < m.height and 0 <= c < m.width and self.ids[r, c] >= 0:
                    node = int(self.ids[r, c])
                    if math.isfinite(dist[node]):
                        cx, cy = m.cell_centers(r, c)
                        dd = math.hypot(cx - x, cy - y)
                        if dd < best_d and dd <= radius:
                            best, best_d = node, dd
        return best

    def plan(self, goal: tuple[float, float]) -> NavigationFunction:
        """Dijkstra from ``goal`` (x, y in m) over the whole grid.

        Raises ``ValueError`` if the goal is not on a traversable cell (outside the map, in an
        obstacle or within the inflation radius of one)."""
        node = self.node_of(*goal)
        if node < 0:
            raise ValueError(f"goal {goal} is not traversable on the inflated map")
        dist, pred = dijkstra(self.graph, directed=False, indices=node,
                              return_predecessors=True)
        return NavigationFunction(self, (float(goal[0]), float(goal[1])), dist,
                                  pred.astype(np.int64))


@dataclass(frozen=True)
class ControllerParams:
    """Local controller settings (Safe-ROS DWA limits where they exist).

    ``max_v`` m/s, ``max_w`` rad/s, ``acc_v`` m/s^2, ``acc_w`` rad/s^2, ``period`` s (10 Hz);
    ``lookahead`` m (pure pursuit); ``rotate_threshold`` rad (turn in place above this heading
    error); ``goal_tolerance`` m (``xy_goal_tolerance``; the goal's yaw is ignored, as Safe-ROS's
    ``yaw_goal_tolerance: 6.28``); ``slow_range`` m / ``slow_speed`` m/s (speed-limit zone);
    ``stuck_timeout`` s without ``progress`` m of cost-to-go progress aborts the goal."""

    max_v: float = 0.5
    max_w: float = 0.5
    acc_v: float = 0.5
    acc_w: float = 0.5
    period: float = 0.1
    lookahead: float = 0.45
    rotate_threshold: float = 0.9
    goal_tolerance: float = 0.2
    slow_range: float = 0.95
    slow_speed: float = 0.1
    stuck_timeout: float = 12.0
    progress: float = 0.05


class LocalController:
    """Pure-pursuit path tracking in a dynamic window (see module docstring)."""

    def __init__(self, params: ControllerParams = ControllerParams()):
        self.p = params
        self.nav: NavigationFunction | None = None
        self.best_cost = math.inf
        self.best_time = 0.0

    def set_goal(self, nav: NavigationFunction, t: float) -> None:
        """Track a new navigation function from sim time ``t`` s."""
        self.nav = nav
        self.best_cost = math.inf
        self.best_time = t

    def goal_reached(self, x: float, y: float) -> bool:
        """Whether ``(x, y)`` (estimated, ``map``) is within ``goal_tolerance`` of the goal."""
        assert self.nav is not None  # (set_goal came first)
        g = self.nav.goal
        return math.hypot(g[0] - x, g[1] - y) <= self.p.goal_tolerance

    def stuck(self, t: float) -> bool:
        """Whether the goal has made no progress for ``stuck_timeout`` s."""
        return t - self.best_time > self.p.stuck_timeout

    def compute(self, x: float, y: float, yaw: float, v_odom: float, w_odom: float,
                min_range: float, t: float) -> tuple[float, float]:
        """The command ``(v, w)`` (m/s, rad/s) for the estimated pose ``(x, y, yaw)`` (``map``),
        the odometry twist and the nearest valid scan range ``min_range`` m, at sim time ``t``.
        Returns ``(0, 0)`` if there is no path."""
        p = self.p
        nav = self.nav
        assert nav is not None  # (set_goal came first)
        c2g = nav.cost_to_go(x, y)
        if c2g < self.best_cost - p.progress:
            self.best_cost = c2g
            self.best_time = t
        path = nav.path_from(x, y, max_length=p.lookahead + 0.5)
        if len(path) == 0:
            return 0.0, 0.0
        goal = nav.goal
        d_goal = math.hypot(goal[0] - x, goal[1] - y)
        # lookahead point: first path point at least `lookahead` away (or the path's end)
        d = np.hypot(path[:, 0] - x, path[:, 1] - y)
        far = np.nonzero(d >= p.lookahead)[0]
        lx, ly = path[far[0]] if far.size else path[-1]
        alpha = wrap_angle(math.atan2(ly - y, lx - x) - yaw)
        L = max(math.hypot(lx - x, ly - y), 1e-6)
        if abs(alpha) > p.rotate_threshold:
            v_des = 0.0
            w_des = math.copysign(p.max_w, alpha) * min(1.0, abs(alpha) / 0.6)
        else:
            v_des = p.max_v * max(0.2, math.cos(alpha))
            v_des = min(v_des, math.sqrt(2.0 * p.acc_v * 0.8 * max(d_goal - 0.02, 0.0)))
            if min_range < p.slow_range:
                v_des = min(v_des, p.slow_speed)
            curv = 2.0 * math.sin(alpha) / L
            w_des = v_des * curv
            if abs(w_des) > p.max_w:  # keep the curvature, slow down
                v_des *= p.max_w / abs(w_des)
                w_des = math.copysign(p.max_w, w_des)
        # dynamic window around the measured twist
        dv, dw = p.acc_v * p.period, p.acc_w * p.period
        v = min(max(v_des, v_odom - dv), v_odom + dv)
        w = min(max(w_des, w_odom - dw), w_odom + dw)
        v = min(max(v, -p.max_v), p.max_v)
        w = min(max(w, -p.max_w), p.max_w)
        if min_range < p.slow_range:
            v = min(max(v, -p.slow_speed), p.slow_speed)
        return float(v), float(w)


#: The inspection points of the paper's mission (Safe-ROS ``simple_navigation_goals.cpp``).
INSPECTION_POINTS: tuple[tuple[float, float], ...] = ((0.0, 0.0), (2.30, -1.11), (2.61, 2.42))


@dataclass
class Mission:
    """The route: ``points`` in order, then ``home``; ``dwell`` s of inspection at each point.
    ``index`` is the current goal (``len(points)`` is home); ``done``/``aborted`` end it."""

    points: Sequence[tuple[float, float]]
    home: tuple[float, float]
    dwell: float = 1.0
    index: int = 0
    done: bool = False
    aborted: bool = False
    abort_reason: str = ""
    #: (goal index, t s, x m, y m) of each arrival, ground truth
    reached: list[tuple[int, float, float, float]] = field(default_factory=list)

    @property
    def goals(self) -> list[tuple[float, float]]:
        """All goals in order, home last."""
        return list(self.points) + [(self.home[0], self.home[1])]

    @property
    def current(self) -> tuple[float, float]:
        """The current goal (x, y) in m."""
        return self.goals[self.index]
