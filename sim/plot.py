"""Draw a run on the map (matplotlib, Agg backend): trajectory, obstacles, inspection points,
where the SIF fired, and the time series the requirements talk about."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

from fretc.sim.simulation import RunResult  # noqa: E402
from fretc.sim.world import OCCUPIED, UNKNOWN  # noqa: E402


def _footprint(x, y, yaw, hl, hw):
    c, s = np.cos(yaw), np.sin(yaw)
    pts = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)])
    return np.column_stack([x + pts[:, 0] * c - pts[:, 1] * s, y + pts[:, 0] * s + pts[:, 1] * c])


def _spans(times, values):
    """Intervals [t0, t1) where a sample-and-hold boolean series is true."""
    out, start = [], None
    for t, v in zip(times, values):
        if v and start is None:
            start = t
        elif not v and start is not None:
            out.append((start, t))
            start = None
    return out, start


def _stop_clusters(points, radius=1.2):
    """Greedy clusters of 2-D points (list of index lists), biggest first."""
    left = list(range(len(points)))
    out = []
    while left:
        seed = left.pop(0)
        members = [seed]
        for j in list(left):
            if min(np.hypot(*(points[j] - points[k])) for k in members) <= radius:
                members.append(j)
                left.remove(j)
        out.append(members)
    return sorted(out, key=len, reverse=True)


def _draw_zoom(ax, res: RunResult, img, stop_idx, release_idx):
    """Inset magnifying the biggest cluster of SIF stops (at least 3 of them)."""
    tr = res.trace
    xs, ys = np.asarray(tr.x), np.asarray(tr.y)
    pts = np.column_stack([xs[stop_idx], ys[stop_idx]]) if stop_idx else np.zeros((0, 2))
    clusters = _stop_clusters(pts)
    if not clusters or len(clusters[0]) < 3:
        return
    sel = pts[clusters[0]]
    lo, hi = sel.min(axis=0) - 0.6, sel.max(axis=0) + 0.6
    cx, cy = (lo + hi) / 2.0
    half_w, half_h = (hi - lo) / 2.0
    half_h = max(half_h, 1.05)
    ratio = 1.26  # width / height of the inset box below, in data units
    if half_w / half_h > ratio:
        half_h = half_w / ratio
    else:
        half_w = half_h * ratio
    axins = ax.inset_axes([0.075, 0.625, 0.42, 0.355])
    axins.imshow(img, cmap="gray", vmin=0, vmax=1, origin="lower", extent=res.world.omap.extent,
                 interpolation="nearest")
    axins.scatter(xs, ys, c=tr.t, cmap="viridis", s=2, zorder=5)
    for b in res.world.barrels:
        axins.add_patch(Circle((b.x, b.y), b.radius, fc="tab:orange", ec="k", lw=1.0, zorder=4))
    for i in stop_idx:
        axins.add_patch(Polygon(_footprint(xs[i], ys[i], tr.yaw[i], 0.21, 0.165), closed=True,
                                fc="none", ec="red", lw=0.9, zorder=7))
        axins.plot(xs[i], ys[i], "x", color="red", ms=6, mew=1.8, zorder=9)
    for i in release_idx:
        axins.plot(xs[i], ys[i], "o", color="tab:green", ms=3.5, mec="k", mew=0.4, zorder=8)
    for gx, gy in res.goals[:-1]:
        axins.plot(gx, gy, marker="*", ms=13, color="gold", mec="k", zorder=6)
    axins.set_xlim(cx - half_w, cx + half_w)
    axins.set_ylim(cy - half_h, cy + half_h)
    axins.set_aspect("equal")
    axins.tick_params(labelsize=6)
    axins.text(0.98, 0.97, "zoom: footprints at\nSIF stops, releases", transform=axins.transAxes,
               fontsize=7, va="top", ha="right",
               bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
    ax.indicate_inset_zoom(axins, edgecolor="0.3")


def draw_run(res: RunResult, path: str | Path, dpi: int = 110) -> None:
    """Write a PNG of run ``res`` to ``path``: left, the room (zoomed on the route) with the
    ground-truth trajectory coloured by time, footprints at SIF stops, unmapped objects,
    inspection points and home; right, min valid scan range vs the threshold, commanded
    (filtered) and true speed, and ground-truth clearance, with stop requests shaded."""
    fig = plt.figure(figsize=(14, 7.2), dpi=dpi)
    gs = fig.add_gridspec(3, 2, width_ratios=[1.05, 1.0], hspace=0.32, wspace=0.18,
                          left=0.05, right=0.98, top=0.9, bottom=0.08)
    ax = fig.add_subplot(gs[:, 0])
    img = _draw_map(ax, res.world.omap)
    _draw_objects(ax, res)
    _draw_trajectory(fig, ax, res)
    _draw_goals(ax, res)
    _draw_sif(ax, res, img)
    _draw_time_series(fig, gs, res)
    reached = ", ".join(f"{'P' + str(g + 1) if g < len(res.goals) - 1 else 'home'}@{tt:.1f}s"
                        for g, tt, _, _ in res.reached)
    clr = ("<= 0 (contact)" if res.min_clearance <= 0 else f"{res.min_clearance:.2f} m")
    fig.suptitle(f"fretc sim — scenario {res.scenario.name} (seed {res.seed}, threshold "
                 f"{res.threshold:g} m): {res.outcome} after {res.duration:.1f} s; reached "
                 f"{reached or 'nothing'}; min clearance {clr}\n{res.scenario.description}",
                 fontsize=10.5)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def _draw_map(ax, m):
    """The occupancy map (free white, unknown grey, occupied black), zoomed on the route;
    returns the image drawn."""
    img = np.full(m.grid.shape, 1.0)
    img[m.grid == UNKNOWN] = 0.72
    img[m.grid == OCCUPIED] = 0.0
    ax.imshow(img, cmap="gray", vmin=0, vmax=1, origin="lower", extent=m.extent,
              interpolation="nearest")
    ax.set_xlim(-2.6, 5.4)
    ax.set_ylim(-3.9, 3.7)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (map)")
    ax.set_ylabel("y [m] (map)")
    ax.grid(alpha=0.25)
    return img


def _draw_objects(ax, res: RunResult) -> None:
    """Moved (ghost) objects, unmapped drums, moving objects."""
    tr, w = res.trace, res.world
    for r in res.scenario.removed:
        ax.add_patch(Circle((r.x, r.y), r.radius, fill=False, ls="--", ec="tab:orange", lw=1.2))
        ax.annotate(f"mapped place of\n{r.label.split(' (')[0]}, now empty", (r.x, r.y),
                    xytext=(-16, 0), ha="right", va="center", zorder=10,
                    textcoords="offset points", fontsize=7, color="tab:orange",
                    bbox=dict(fc="white", ec="none", alpha=0.85, pad=1))
    for b in w.barrels:
        ax.add_patch(Circle((b.x, b.y), b.radius, fc="tab:orange", ec="k", lw=1.0, zorder=4))
        moved = any(r.label.split(" (")[0] == b.label for r in res.scenario.removed)
        ax.annotate(b.label + (" (moved here, unmapped)" if moved else " (unmapped)"),
                    (b.x, b.y), xytext=(8, -14),
                    textcoords="offset points", fontsize=8, color="tab:orange")
    for mv in w.movers:
        pts = np.array(mv.waypoints)
        ax.plot(pts[:, 0], pts[:, 1], ls="--", color="tab:purple", lw=1.2)
        for a, b in zip(pts[:-1], pts[1:]):
            mid = a + 0.55 * (b - a)
            ax.annotate("", xy=mid, xytext=a + 0.45 * (b - a),
                        arrowprops=dict(arrowstyle="-|>", color="tab:purple", lw=1.2))
        stop_times = [tc for tc, st in tr.control if st]
        shown = sorted(set([tr.t[0]] + stop_times[:1] + [tr.t[-1]]))
        for tt in shown:
            p = mv.position(tt)
            ax.add_patch(Circle(p, mv.radius, fc="tab:purple", ec="k", lw=0.8, alpha=0.35))
            ax.annotate(f"t={tt:.1f}s", p, xytext=(0, -3), ha="center", va="center",
                        textcoords="offset points", fontsize=6.5)
        ax.annotate(f"{mv.label} ({mv.speed} m/s, from t={mv.t_start:g} s)", pts[0],
                    xytext=(6, 4), textcoords="offset points", fontsize=8, color="tab:purple")

def _draw_trajectory(fig, ax, res: RunResult) -> None:
    """The trajectory coloured by time; underneath, where stop was requested and where
    scans were missing; where the SIF decided a delayed stop."""
    tr = res.trace
    t = np.asarray(tr.t)
    xs, ys = np.asarray(tr.x), np.asarray(tr.y)
    ctl_t = np.array([c[0] for c in tr.control])
    ctl_v = np.array([c[1] for c in tr.control], bool)
    k = np.searchsorted(ctl_t, t, side="right") - 1
    stop_mask = np.where(k >= 0, ctl_v[np.maximum(k, 0)], False) if len(ctl_t) else \
        np.zeros(len(t), bool)
    if stop_mask.any():
        ax.scatter(xs[stop_mask], ys[stop_mask], s=80, color="red", alpha=0.25, lw=0,
                   zorder=4, label="while stop requested")
    sc_ = res.scenario
    if sc_.dropout_start is not None:
        dm = (t >= sc_.dropout_start) & (t < sc_.dropout_start + sc_.dropout_duration)
        ax.scatter(xs[dm], ys[dm], s=110, color="0.3", alpha=0.6, lw=0, zorder=4,
                   label=f"no /scan ({sc_.dropout_duration:g} s)")
    sc = ax.scatter(xs, ys, c=t, cmap="viridis", s=3, zorder=5)
    cax = ax.inset_axes([0.05, 0.29, 0.3, 0.02])
    fig.colorbar(sc, cax=cax, orientation="horizontal")
    cax.tick_params(labelsize=7)
    cax.set_title("sim time [s]", fontsize=7, pad=2)
    if sc_.stop_delay > 0:
        first = True
        for ev in res.sif_events:
            if ev.stop:
                i = min(np.searchsorted(t, ev.t), len(t) - 1)
                ax.plot(xs[i], ys[i], "v", color="tab:orange", ms=7, mec="k", mew=0.5,
                        zorder=9, label=(f"SIF decided stop (published {sc_.stop_delay:g} s "
                                         "later)") if first else None)
                first = False

def _draw_goals(ax, res: RunResult) -> None:
    """The inspection points and home."""
    for i, (gx, gy) in enumerate(res.goals[:-1]):
        ax.plot(gx, gy, marker="*", ms=15, color="gold", mec="k", zorder=6)
        ax.annotate(f"P{i + 1}", (gx, gy), xytext=(8, 6), textcoords="offset points",
                    fontsize=10, weight="bold", zorder=10,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
    hx, hy = res.goals[-1]
    ax.plot(hx, hy, marker="s", ms=10, color="tab:cyan", mec="k", zorder=6)
    ax.annotate("home", (hx, hy), xytext=(7, -14), textcoords="offset points", fontsize=10)

def _draw_sif(ax, res: RunResult, img) -> None:
    """Where the SIF fired (stop published) and was released, the contact, the footprint
    at the end, the legend and the zoom on the stops."""
    tr = res.trace
    t = np.asarray(tr.t)
    hl, hw = 0.21, 0.165
    first = True
    for (tc, stop) in tr.control:
        if not stop:
            continue
        i = min(int(np.searchsorted(t, tc)), len(t) - 1)
        ax.add_patch(Polygon(_footprint(tr.x[i], tr.y[i], tr.yaw[i], hl, hw), closed=True,
                             fc="none", ec="red", lw=1.0, zorder=7))
        ax.plot(tr.x[i], tr.y[i], "x", color="red", ms=8, mew=2.2, zorder=9,
                label="SIF stop published" if first else None)
        first = False
    first = True
    for (tc, stop) in tr.control[1:]:
        if stop:
            continue
        i = min(int(np.searchsorted(t, tc)), len(t) - 1)
        ax.plot(tr.x[i], tr.y[i], "o", color="tab:green", ms=4, mec="k", mew=0.4, zorder=8,
                label="stop released (false)" if first else None)
        first = False
    if res.contact is not None:
        ct, cx, cy = res.contact
        ax.plot(cx, cy, marker="X", ms=9, color="magenta", mec="k", zorder=9,
                label=f"robot centre at contact, t={ct:.2f} s")
    i_end = len(t) - 1
    ax.add_patch(Polygon(_footprint(tr.x[i_end], tr.y[i_end], tr.yaw[i_end], hl, hw),
                         closed=True, fc="tab:blue", alpha=0.5, ec="k", zorder=7))
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower left", fontsize=8, framealpha=0.9)
    ax.set_title("ground-truth trajectory (robot footprint at the end, blue)", fontsize=10)
    stop_idx = [min(np.searchsorted(t, tc), len(t) - 1) for tc, st in tr.control if st]
    release_idx = [min(np.searchsorted(t, tc), len(t) - 1) for tc, st in tr.control[1:]
                   if not st]
    _draw_zoom(ax, res, img, stop_idx, release_idx)


def _draw_time_series(fig, gs, res: RunResult) -> None:
    """Right: min valid scan range vs the threshold, commanded and true speed, clearance,
    with the stop requests shaded."""
    tr = res.trace
    stops = [(tc, s) for tc, s in tr.control]
    ctl_t = [c[0] for c in stops] + [tr.t[-1]]
    ctl_v = [c[1] for c in stops] + [stops[-1][1] if stops else False]
    spans, open_start = _spans(ctl_t, ctl_v)
    if open_start is not None:
        spans.append((open_start, tr.t[-1]))

    def shade(a, label=False):
        for k, (a0, a1) in enumerate(spans):
            a.axvspan(a0, a1, color="red", alpha=0.13, lw=0,
                      label="stop requested (/gwendolen_control)" if k == 0 and label else None)

    a1 = fig.add_subplot(gs[0, 1])
    smin = np.asarray(tr.scan_min)
    a1.plot(tr.scan_t, smin, ".", ms=2.5, color="tab:blue", label="min valid /scan range")
    a1.axhline(res.threshold, color="red", ls="--", lw=1, label=f"threshold {res.threshold:g} m")
    if res.scenario.dropout_start is not None:
        d0 = res.scenario.dropout_start
        a1.axvspan(d0, d0 + res.scenario.dropout_duration, color="gray", alpha=0.3,
                   label="no /scan")
    shade(a1, label=True)
    a1.set_ylim(0, 2.5)
    a1.set_ylabel("range [m]")
    a1.legend(loc="upper right", fontsize=7, ncol=2)
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.step(tr.cmd_t, np.abs(tr.cmd_v), where="post", color="tab:green", lw=1,
            label="|/cmd_vel_filtered linear.x|")
    a2.plot(tr.t, np.abs(tr.v), color="k", lw=0.8, alpha=0.7, label="true |v|")
    shade(a2)
    a2.set_ylim(-0.02, 0.6)
    a2.set_ylabel("speed [m/s]")
    a2.legend(loc="upper right", fontsize=7)
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(tr.t, tr.clearance, color="tab:purple", lw=1, label="/ground_truth/clearance")
    a3.axhline(0.0, color="k", lw=0.8)
    shade(a3)
    a3.set_ylim(min(-0.05, float(np.min(tr.clearance)) - 0.05), 1.8)
    a3.set_ylabel("clearance [m]")
    a3.set_xlabel("sim time [s]")
    a3.legend(loc="upper right", fontsize=7)
    for a in (a1, a2):
        plt.setp(a.get_xticklabels(), visible=False)
    a1.set_xlim(0, tr.t[-1])
