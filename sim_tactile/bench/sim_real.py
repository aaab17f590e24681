"""Simulated against real streams of the same sensor: ``sim-tactile bench sim-real``.

For each sensor with real recordings (the public BioTac and iCub slides of seed 000), the
real slides and the simulated slides of the task that reproduces their protocol in
simulation (``textures20-biotac19-v2``, ``textures20-icub60-v2``: windows as long as the real
ones, all on texture) are reduced to the same statistics,
and their distributions over slides are set side by side:

- per slide, averaged over channels: the **mean** level, the **maximum**, the **temporal
  standard deviation**, the **noise** (standard deviation of first differences over
  sqrt(2)), the **spectral slope** (of the log power spectrum against log frequency, between
  :data:`SLOPE_BAND_HZ`), and the **correlation** between channels (mean over pairs);
- per data set: the **class separability** of the time-averaged channels (between-class
  over within-class spread, the traces of their scatter matrices).

Each simulated sensor may carry a calibration (``--sensor-config``, once per sensor, from ``sim-tactile
calibrate``); then the table has a column for the preset and one for the calibrated sensor.
A ratio within [1/2, 2] of the real median is marked as within a factor of 2.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..datasets.real import load_biotac, load_icub
from ..errors import ConfigError
from ..sensors.calibration import load_calibration
from ..tasks import DataRequest, get_task

#: Frequency band of the spectral slope [Hz] (below the iCub's 25 Hz Nyquist).
SLOPE_BAND_HZ = (1.0, 20.0)
#: A statistic agrees when the simulated median is within this factor of the real one.
FACTOR = 2.0
#: The sensors with real data, the task that simulates each, and its real-data loader.
SENSORS = {
    "biotac19": ("textures20-biotac19-v2", load_biotac),
    "icub60": ("textures20-icub60-v2", load_icub),
}
STATS = ("mean", "max", "temporal_std", "noise", "spectral_slope", "channel_correlation")


def slide_stats(x: np.ndarray, rate_hz: float) -> dict[str, np.ndarray]:
    """The per-slide statistics of ``x`` (slides, time, channels)."""
    x = np.asarray(x, dtype=float)
    n, T, C = x.shape
    out = {
        "mean": x.mean(axis=(1, 2)),
        "max": x.max(axis=(1, 2)),
        "temporal_std": x.std(axis=1).mean(axis=1),
        "noise": (np.diff(x, axis=1).std(axis=1) / np.sqrt(2)).mean(axis=1),
    }
    from scipy.signal import welch

    f, p = welch(x - x.mean(axis=1, keepdims=True), fs=rate_hz, axis=1, nperseg=min(T, 64))
    band = (f >= SLOPE_BAND_HZ[0]) & (f <= min(SLOPE_BAND_HZ[1], rate_hz / 2))
    pm = p[:, band, :].mean(axis=2)  # (slides, freqs), averaged over channels
    lf = np.log10(f[band])
    slopes = np.full(n, np.nan)
    ok = (pm > 0).all(axis=1)
    if band.sum() >= 3:
        slopes[ok] = np.polyfit(lf, np.log10(pm[ok]).T, 1)[0]
    out["spectral_slope"] = slopes
    corr = np.full(n, np.nan)
    for k in range(n):
        s = x[k].std(axis=0)
        live = s > 0
        if live.sum() >= 2:
            c = np.corrcoef(x[k][:, live].T)
            corr[k] = np.nanmean(c[np.triu_indices(int(live.sum()), 1)])
    out["channel_correlation"] = corr if C > 1 else np.full(n, np.nan)
    return out


def separability(x: np.ndarray, y: np.ndarray) -> float:
    """Between-class over within-class spread of the time-averaged channels."""
    m = np.asarray(x, dtype=float).mean(axis=1)
    mu = m.mean(axis=0)
    sb = sw = 0.0
    for c in np.unique(y):
        mc = m[y == c]
        sb += len(mc) * float(((mc.mean(axis=0) - mu) ** 2).sum())
        sw += float(((mc - mc.mean(axis=0)) ** 2).sum())
    return sb / sw if sw > 0 else float("nan")


def _summary(stats: dict[str, np.ndarray], sep: float) -> dict:
    out = {}
    for k in STATS:
        v = stats[k][np.isfinite(stats[k])]
        out[k] = (
            {
                "median": float(np.median(v)),
                "q25": float(np.quantile(v, 0.25)),
                "q75": float(np.quantile(v, 0.75)),
            }
            if v.size
            else None
        )
    out["class_separability"] = {"median": sep, "q25": sep, "q75": sep}
    return out


def _subset(ds, per_class: int):
    keep = np.concatenate(
        [np.flatnonzero(ds.labels == c)[:per_class] for c in np.unique(ds.labels)]
    )
    return ds.data[keep], ds.labels[keep]


def _simulated(task_id: str, per_class: int, cal, log) -> tuple[np.ndarray, np.ndarray, float]:
    spec = get_task(task_id)
    ss = replace(spec.get_data, quick_slides=per_class, quick_plates=None, calibration=cal)
    ds = ss(DataRequest(None, True, 0, log))
    return ds.data, ds.labels, ds.rate_hz


def run_sim_real(
    data: str | Path,
    out: str | Path,
    *,
    sensors: tuple[str, ...] = ("biotac19", "icub60"),
    slides: dict[str, int] | None = None,
    sensor_config: str | Path | list | tuple | None = None,
    log=print,
) -> dict:
    """The table (as JSON data) and figure of the comparison; see the module."""
    t0 = time.perf_counter()
    slides = {"biotac19": 5, "icub60": 2} | (slides or {})
    configs = (
        []
        if sensor_config is None
        else [sensor_config]
        if isinstance(sensor_config, str | Path)
        else list(sensor_config)
    )
    cals = {}
    for c in configs:
        cal = load_calibration(c)
        if cal.sensor not in sensors:
            raise ConfigError(
                f"--sensor-config {str(c)!r} calibrates {cal.sensor!r}, which is not among "
                f"{list(sensors)}"
            )
        if cal.sensor in cals:
            raise ConfigError(
                f"--sensor-config: two calibrations of {cal.sensor!r}; valid: one per sensor"
            )
        cals[cal.sensor] = cal
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"sensors": {}, "factor": FACTOR, "figures": []}
    panels = []
    for name in sensors:
        if name not in SENSORS:
            raise ConfigError(f"sensor {name!r} has no real data here; valid: {list(SENSORS)}")
        task_id, loader = SENSORS[name]
        real = loader(data)
        xr, yr = _subset(real, slides[name])
        log(f"sim-real: {name}: {len(yr)} real slides; simulating {slides[name]} per plate")
        cols = {"real": _summary(slide_stats(xr, real.rate_hz), separability(xr, yr))}
        raw = {"real": slide_stats(xr, real.rate_hz)}
        xs, ys, rate = _simulated(task_id, slides[name], None, log)
        cols["simulated"] = _summary(slide_stats(xs, rate), separability(xs, ys))
        raw["simulated"] = slide_stats(xs, rate)
        if name in cals:
            xc, yc, rate = _simulated(task_id, slides[name], cals[name], log)
            cols["calibrated"] = _summary(slide_stats(xc, rate), separability(xc, yc))
            raw["calibrated"] = slide_stats(xc, rate)
        doc["sensors"][name] = {
            "task": task_id,
            "n_real": int(len(yr)),
            "n_simulated": int(len(ys)),
            "units": real.units,
            "columns": cols,
        }
        panels.append((name, raw))
    doc["wall_s"] = round(time.perf_counter() - t0, 1)
    fig = out / "sim_real.png"
    _figure(panels, fig)
    doc["figures"].append(str(fig))
    return doc


def _ratio(sim: dict | None, real: dict | None) -> float | None:
    if not sim or not real or real["median"] == 0:
        return None
    return sim["median"] / real["median"]


def table(doc: dict) -> str:
    """The comparison as a Markdown table: real median [IQR], each simulated column's median
    and its ratio to the real one (marked when outside a factor of 2)."""
    lines = []
    for name, s in doc["sensors"].items():
        cols = [c for c in s["columns"] if c != "real"]
        lines.append(
            f"{name} ({s['task']}; {s['n_real']} real, {s['n_simulated']} simulated slides; {s['units']})"
        )
        lines.append("")
        lines.append(
            "| statistic | real median [IQR] | " + " | ".join(f"{c} (x real)" for c in cols) + " |"
        )
        lines.append("|---|---|" + "---|" * len(cols))
        for k in (*STATS, "class_separability"):
            r = s["columns"]["real"][k]
            cells = []
            for c in cols:
                m = s["columns"][c][k]
                q = _ratio(m, r)
                flag = "" if q is None or 1 / doc["factor"] <= q <= doc["factor"] else " **!**"
                cells.append(
                    "-"
                    if m is None
                    else f"{m['median']:.3g} ({'-' if q is None else f'{q:.2g}'}){flag}"
                )
            real = "-" if r is None else f"{r['median']:.3g} [{r['q25']:.3g}, {r['q75']:.3g}]"
            lines.append(f"| {k} | {real} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def _figure(panels, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        len(panels), len(STATS), figsize=(3.2 * len(STATS), 2.6 * len(panels)), squeeze=False
    )
    colors = {"real": "k", "simulated": "tab:orange", "calibrated": "tab:blue"}
    for row, (name, raw) in zip(axes, panels, strict=True):
        for ax, k in zip(row, STATS, strict=True):
            vals = [v[k][np.isfinite(v[k])] for v in raw.values()]
            allv = (
                np.concatenate([v for v in vals if v.size])
                if any(v.size for v in vals)
                else np.zeros(1)
            )
            lo, hi = np.quantile(allv, [0.01, 0.99]) if allv.size else (0, 1)
            bins = np.linspace(lo, hi if hi > lo else lo + 1, 30)
            for label, vv in zip(raw, vals, strict=True):
                if vv.size:
                    ax.hist(
                        vv,
                        bins=bins,
                        histtype="step",
                        color=colors[label],
                        label=label,
                        density=True,
                    )
            ax.set_title(f"{name}: {k}", fontsize=9)
            ax.tick_params(labelsize=7)
        row[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
