"""The speed-against-error table and its Pareto figure."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from ..sim.plan.fidelity import LEVELS
from ..tables import markdown_table


def pct(x: float | None) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.2%}"


def _num(x: float | None, scale: float = 1.0, fmt: str = ".3g") -> str:
    return "-" if x is None else format(x * scale, fmt)


def table_rows(rows: list[dict]) -> list[list[str]]:
    """The table's cells, one list per row (header first)."""
    head = [
        "scene",
        "level",
        "setting",
        "dt [ms]",
        "node pitch [mm]",
        "nodes",
        "RTF",
        "cost [s/s]",
        "error vs L2",
        "error vs physics (largest taxel)",
        "error vs closed form",
        "note",
    ]
    out = [head]
    for r in rows:
        note = r.get("error") or r.get("note") or ""
        a = r.get("analytic") or {}
        if not note and r["outcome"] == "ok":
            if r.get("static"):
                note = (
                    f"solve {r['wall_s']:.2f} s; a {a['radius_error']:+.1%}, "
                    f"p0 {a['peak_error']:+.1%}"
                )
            elif a.get("period_s") is not None:
                note = (
                    f"period {a['period_s'] * 1e3:.2f} ms vs {a['closed_form_s'] * 1e3:.2f} ms "
                    f"over {a['periods']:.1f} periods, ripple {a['ripple']:.1%}; pad speed "
                    f"{a['speed_error']:+.1%} off command"
                )
            elif a.get("reason"):
                note = a["reason"]
            elif a.get("what"):
                note = a["what"]
        if r.get("same_as"):
            note = f"also {', '.join(r['same_as'])} (same step, whole steps per sample); " + note
        out.append(
            [
                r["scene"],
                r["fidelity"],
                r["setting"],
                _num(r.get("dt_s"), 1e3),
                _num(r.get("pitch_m"), 1e3),
                str(r.get("n_nodes", "-")),
                _num(r.get("rtf")),
                _num(r.get("cost_s_per_s")),
                pct(r.get("error_vs_reference")),
                _physics_cell(r),
                pct(r.get("error_vs_analytic")),
                note,
            ]
        )
    return out


def _physics_cell(r: dict) -> str:
    if r.get("error_vs_physics") is None:
        return "-"
    return f"{pct(r['error_vs_physics'])} ({pct(r.get('physics_max'))})"


def _physics_lines(rows: list[dict]) -> list[str]:
    """One line per scene on its physics reference (or why there is none)."""
    out, seen = [], set()
    for r in rows:
        if r["scene"] in seen:
            continue
        if r.get("physics"):
            seen.add(r["scene"])
            ph = r["physics"]
            out.append(
                f"- {r['scene']}: Tamaas at {ph['spacing_m'] * 1e3:g} mm, pad offsets "
                f"{', '.join(f'{o * 1e3:g}' for o in ph['offsets_m'])} mm, {ph['wall_s']:.0f} s; "
                f"on a grid twice as coarse its taxel loads move by {pct(ph['ref_change'])}"
            )
        elif r.get("physics_note"):
            seen.add(r["scene"])
            out.append(f"- {r['scene']}: {r['physics_note']}")
    return out


def markdown(doc: dict) -> str:
    cells = table_rows(doc["rows"])
    lines = [
        "# Speed against error (`sim-tactile bench speed-error`)",
        "",
        f"{'quick' if doc['quick'] else 'full'} run, {doc['wall_s']:.0f} s on "
        f"{doc['machine']['cpus']} cores (load average at start "
        f"{doc['machine']['loadavg_start']}, at end {doc['machine']['loadavg_end']}).",
        "",
        "RTF: simulated slide seconds per wall second of the slide loop, one core; cost = 1/RTF "
        "(the press is static: its cost is the wall time of the solve, in the note). Error vs "
        "L2: relative L2 norm of the ideal (time x taxel) recording against the L2 reference "
        "(press: of the dense grid's pressure against the finest node pitch). Error vs closed "
        "form: period of the probe taxel's signal while the whole pad is over the texture, "
        "against feature spacing / pad speed; Hertz: the larger of the contact-radius and "
        "peak-pressure errors. The reference (error 0) is drawn at the figure's left edge. "
        "Error vs physics: the configuration's skin in static presses at a few pad offsets "
        "against an independent half-space solver (Tamaas's boundary elements on a fine "
        "grid), both read by the sensor's taxels: relative norm over offsets x taxels, and in "
        "brackets the largest taxel difference in units of the largest reference load. In the "
        "figure, hollow markers.",
        "",
        *markdown_table(cells[0], cells[1:]),
    ]
    phys = _physics_lines(doc["rows"])
    if phys:
        lines += ["", "The references against physics:", *phys]
    if doc.get("left_out"):
        lines += ["", "Not run:"]
        lines += [f"- {x['scene']}: {x['reason']}" for x in doc["left_out"]]
    return "\n".join(lines) + "\n"


def pareto_front(errors: Sequence[float], costs: Sequence[float]) -> list[int]:
    """Indices of the configurations no other beats on both error and cost (both lower is
    better), in order of rising cost."""
    order = sorted(range(len(costs)), key=lambda i: (costs[i], errors[i]))
    front, best = [], math.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


_MARKERS = {"L0": "o", "L1": "s", "L2": "*", "auto": "D"}
_COLOURS = {"L0": "tab:orange", "L1": "tab:blue", "L2": "tab:green", "auto": "tab:red"}


def _scatter_levels(ax, points: list[tuple[float, float, str]], hollow: bool = False) -> None:
    """(error, cost, level) points, one marker series per level: filled against L2, hollow
    against physics."""
    for level in (*LEVELS, "auto"):  # auto: the default where it is not L1's own grid
        pts = [(e, c) for e, c, lv in points if lv == level]
        if not pts:
            continue
        style = (
            {"facecolors": "none", "edgecolors": _COLOURS[level]}
            if hollow
            else {"color": _COLOURS[level]}
        )
        ax.scatter(
            [e for e, _ in pts],
            [c for _, c in pts],
            marker=_MARKERS[level],
            s=110 if level == "L2" else 45,
            label=f"{level} vs physics" if hollow else level,
            zorder=3,
            **style,
        )


def plot_pareto(rows: list[dict], path: str | Path) -> Path:
    """One panel per scene: cost against error vs the reference, log axes, one marker series
    per level, the Pareto front drawn through its points; the reference (error 0) is drawn
    at the left edge."""
    from matplotlib.figure import Figure

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    ncols = 2 if len(scenes) > 1 else 1
    nrows = max(1, math.ceil(len(scenes) / ncols))
    fig = Figure(figsize=(6.2 * ncols, 4.6 * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax in axes[len(scenes) :]:
        ax.set_visible(False)
    for ax, scene in zip(axes, scenes, strict=False):
        srows = [r for r in rows if r["scene"] == scene]
        ok = [
            r
            for r in srows
            if r["outcome"] == "ok"
            and r.get("error_vs_reference") is not None
            and math.isfinite(r["error_vs_reference"])
        ]
        static = any(r.get("static") for r in srows)
        cost = [r["cost_s"] if static else r["cost_s_per_s"] for r in ok]
        err = [r["error_vs_reference"] for r in ok]
        pos = [e for e in err if e > 0]
        floor = min(pos) / 3 if pos else 1e-3
        xs = [e if e > 0 else floor for e in err]
        _scatter_levels(ax, [(xs[i], cost[i], r["fidelity"]) for i, r in enumerate(ok)])
        phys = [
            (r["error_vs_physics"], cost[i], r["fidelity"])
            for i, r in enumerate(ok)
            if r.get("error_vs_physics") is not None
        ]
        _scatter_levels(ax, phys, hollow=True)
        for i, r in enumerate(ok):
            label = "reference (error 0)" if err[i] == 0 else r["setting"]
            ax.annotate(
                label,
                (xs[i], cost[i]),
                textcoords="offset points",
                xytext=(5, 4) if i % 2 == 0 else (5, -10),  # alternate: fewer overlaps
                fontsize=7,
                color="0.3",
            )
        front = pareto_front(err, cost)
        if front:
            front.sort(key=lambda i: xs[i])  # the attainment staircase, left to right
            fx = [xs[i] for i in front]
            fy = [cost[i] for i in front]
            ax.step(
                fx, fy, where="post", color="k", lw=1.0, ls="--", zorder=2, label="Pareto front"
            )
            ax.scatter(fx, fy, s=190, facecolors="none", edgecolors="k", lw=1.2, zorder=4)
        failed = [r for r in srows if r["outcome"] != "ok"]
        if failed:
            ax.text(  # lower left: nothing lies beyond the front there
                0.02,
                0.02,
                "stopped with an error (see table):\n"
                + "\n".join(f"{r['fidelity']} {r['setting']}" for r in failed),
                transform=ax.transAxes,
                ha="left",
                va="bottom",
                fontsize=7,
                color="tab:red",
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(
            "error (relative L2 norm): filled vs the L2 reference, hollow vs physics (Tamaas)"
            if phys
            else "error vs L2 reference (relative L2 norm)"
        )
        ax.set_ylabel(
            "wall time of the static solve [s]"
            if static
            else "cost: wall s per simulated s (1/RTF)"
        )
        ax.set_title(scene, fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("sim-tactile: speed against error of the fidelity levels (lower left is better)")
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
