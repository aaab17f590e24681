"""The dataset card (``README.md`` with the YAML header the Hub reads, written with
``huggingface_hub``'s ``DatasetCardData``) and the Croissant metadata (built with
``mlcroissant``) of an export (:mod:`.hub`): what the set is, how it was made (sensor, plates,
protocol, fidelity and the model's measured error, the package's version), its columns, its
license and how to cite it."""

from __future__ import annotations

import json
from pathlib import Path

from ..datasets import SlideStore
from ..datasets.store import PARAM_NAMES
from ..errors import SimTactileError, require

#: The license of a simulated data set's card (the data are the package's output; a user
#: may publish them under another); a recorded data set keeps its release's license.
SIM_LICENSE = "cc-by-4.0"
CITATION = """@software{sim_tactile,
  title = {sim_tactile: a physics-simulated benchmark for tactile texture perception},
  version = {VERSION},
  note = {CadQuery plates, a MuJoCo soft finger with a taxel array, neuromorphic encoders}
}"""
#: The drawn slide parameters' columns (``PARAM_NAMES``; a new one needs its line here).
PARAM_DOCS = {
    "speed_m_s": "the slide's drawn speed [m/s] (NaN for recordings)",
    "force_n": "the slide's drawn normal force [N] (NaN for recordings)",
    "offset_y_m": "the slide's drawn offset across the slide [m] (NaN for recordings)",
}
#: The export's columns: name, type, meaning.
COLUMNS = (
    ("data", "list of T lists of N float32", "the slide's samples (time x channel), in `units`"),
    ("label", "class label", "the plate (class) of the slide"),
    ("index", "int64", "the slide's number in the store"),
    ("slide", "int64", "the slide's number within its class"),
    ("seed", "uint64", "the slide's simulation seed (0 for recordings)"),
    *((k, "float64", PARAM_DOCS[k]) for k in PARAM_NAMES),
)


def _size_category(n: int) -> str:
    return "n<1K" if n < 1000 else "1K<n<10K" if n < 10_000 else "10K<n<100K"


def fidelity_rows(st: SlideStore) -> list[dict]:
    """Each plate's fidelity of a store generated for a task: the skin model's level, its
    node pitch and the measured error of the taxel loads (what ``simulate`` chose for the
    plate's first slide); [] where the store records no task or no simulation."""
    cfg = st.config
    if cfg.get("kind") != "simulated" or not cfg.get("task"):
        return []
    from ..sim.plan.fidelity import choose_fidelity
    from ..slides import SlideSet
    from ..tasks import get_task

    slides = get_task(cfg["task"]).get_data
    if not isinstance(slides, SlideSet):
        return []
    rows, seen = [], set()
    for job in slides.jobs(int(cfg.get("seed") or 0), bool(cfg.get("quick"))):
        if job.plate.name in seen:
            continue
        seen.add(job.plate.name)
        finger = job.finger or job.sensor.finger
        try:
            f = choose_fidelity(
                job.plate,
                job.sensor.layout,
                finger,
                job.protocol,
                job.fidelity,
                pitch_m=job.pitch_m,
            )
        except SimTactileError as exc:
            rows.append({"plate": job.plate.name, "level": "?", "note": str(exc)})
            continue
        rows.append(
            {
                "plate": job.plate.name,
                "level": f.level,
                "pitch_mm": round(f.pitch_m * 1e3, 4),
                "expected_error": None if f.expected_error is None else round(f.expected_error, 4),
            }
        )
    return rows


def _made(st: SlideStore) -> list[str]:
    cfg, meta = st.config, st.meta
    dm = meta.get("dataset_meta") or {}
    out = [f"- Source: {dm.get('source', cfg.get('kind', 'unknown'))}."]
    if cfg.get("kind") == "simulated":
        proto = cfg.get("protocol") or {}
        out.append(
            f"- Sensor: `{cfg.get('sensor')}` ({len(st.channel_names)} channels, "
            f"{st.rate_hz:g} Hz, output in {st.units})."
        )
        out.append(
            "- Plates (one class each): " + ", ".join(f"`{p}`" for p in cfg.get("plates", [])) + "."
        )
        keys = (
            "speed_m_s",
            "force_n",
            "duration_s",
            "speed_jitter",
            "force_jitter",
            "offset_jitter_m",
            "force_control",
        )
        out.append("- Protocol: " + ", ".join(f"{k} {proto[k]}" for k in keys if k in proto) + ".")
        out.append(
            f"- Task: `{cfg.get('task')}`{' (quick)' if cfg.get('quick') else ''}, seed "
            f"{cfg.get('seed')}, {cfg.get('slides_per_plate')} slides per plate."
        )
        rows = fidelity_rows(st)
        if rows:
            out.append(
                "- Fidelity (the skin model's level and node pitch, and the taxel loads' "
                "measured error against the physics reference, per plate):"
            )
            for r in rows:
                err = r.get("expected_error")
                err_s = "not measured" if err is None else f"{100 * err:.1f}%"
                out.append(
                    f"  - `{r['plate']}`: {r['level']}, pitch {r.get('pitch_mm', '?')} mm, "
                    f"error {err_s}"
                )
        else:
            out.append(f"- Fidelity: {cfg.get('fidelity', 'auto')} (per plate: not recorded).")
    versions = meta.get("versions") or {}
    out.append(
        f"- Made by sim_tactile {versions.get('sim_tactile', '?')}; configuration hash "
        f"`{st.config_hash}`, slide code `{meta.get('code_version', '-')}`."
    )
    return out


def content_name(info: dict) -> str:
    """What makes one configuration of an export unique, in one line: its shards' SHA-256
    (the rows a loader reads, byte for byte), the store's configuration hash and slide code
    (what made them) and the split sizes."""
    st: SlideStore = info["store"]
    sizes = ", ".join(f"{k} {s['slides']}" for k, s in info["splits"].items())
    return (
        f"sim_tactile export, configuration {info['config']!r}: content sha256 "
        f"{info['content_sha256']}; configuration hash {st.config_hash}; slide code "
        f"{st.meta.get('code_version', '-')}; splits {sizes}"
    )


def card_data(infos: list[dict], version: str):
    """``huggingface_hub.DatasetCardData`` of an export. Each configuration carries its
    content (:func:`content_name`) as its ``description``, and the ``dataset_info`` block its
    features and split sizes: ``datasets.load_dataset(<folder>)`` keys its cache by the
    folder's name and this YAML (the configurations and the infos), not by the files, so
    what is in the files must be in the YAML. ``load_dataset`` also checks the loaded
    splits' sizes against ``dataset_info``."""
    hub = require("huggingface_hub", "hub")
    hf = require("datasets", "hub")
    infos_mod = require("datasets.info", "hub")
    st0: SlideStore = infos[0]["store"]
    recorded = st0.config.get("kind") != "simulated"
    configs = [
        {
            "config_name": i["config"],
            "description": content_name(i),
            "data_files": [
                {"split": side, "path": f"data/{i['config']}/{side}-*.parquet"}
                for side in i["splits"]
            ],
        }
        for i in infos
    ]
    n = sum(s["slides"] for i in infos for s in i["splits"].values())
    data = hub.DatasetCardData(
        license="other" if recorded else SIM_LICENSE,
        pretty_name=st0.meta.get("name") or "sim_tactile data set",
        size_categories=_size_category(n),
        task_categories=["other"],
        tags=["tactile", "robotics", "neuromorphic", "texture", "time-series"]
        + ([] if recorded else ["simulation"]),
        configs=configs,
    )
    infos_dict = infos_mod.DatasetInfosDict(
        {
            i["config"]: hf.DatasetInfo(
                config_name=i["config"],
                features=i["features"],
                splits=hf.SplitDict.from_split_dict(
                    [
                        {"name": side, "num_bytes": s["bytes"], "num_examples": s["slides"]}
                        for side, s in i["splits"].items()
                    ]
                ),
                download_size=i["download_bytes"],
                dataset_size=sum(s["bytes"] for s in i["splits"].values()),
            )
            for i in infos
        }
    )
    infos_dict.to_dataset_card_data(data)
    return data


def load_snippet(infos: list[dict]) -> list[str]:
    """The card's way to load the export: ``datasets.load_dataset("parquet",
    data_files=...)`` of each configuration's files, under their folder (a loader keys its
    cache by those files and their times, so a new export is read anew)."""
    lines = ["```python", "from datasets import load_dataset", "", 'folder = "."  # this folder']
    for i in infos:
        name = "ds" if len(infos) == 1 else f"ds_{i['config'].replace('-', '_')}"
        lines.append(f"{name} = load_dataset(")
        lines.append('    "parquet",')
        lines.append("    data_files={")
        for side in i["splits"]:
            lines.append(f'        "{side}": f"{{folder}}/data/{i["config"]}/{side}-*.parquet",')
        lines += ["    },", ")"]
    lines.append("```")
    return lines


def card_text(infos: list[dict], version: str) -> str:
    """The card: the YAML header, then what the set is, how it was made, the columns, the
    license and the citation."""
    data = card_data(infos, version)
    st0: SlideStore = infos[0]["store"]
    lines = ["---", data.to_yaml(), "---", "", f"# {data.pretty_name}", ""]
    for i in infos:
        st: SlideStore = i["store"]
        sizes = ", ".join(f"{k} {s['slides']}" for k, s in i["splits"].items())
        t, c = i["shape"]
        lines += [
            f"## Configuration `{i['config']}`",
            "",
            f"{len(st)} slides of {t} samples x {c} channels ({', '.join(st.channel_names[:6])}"
            f"{', ...' if c > 6 else ''}) at {st.rate_hz:g} Hz, in {st.units}; "
            f"{len(st.class_names)} classes: {', '.join(st.class_names)}. Splits: {sizes}"
            + (
                f" (the first split of task `{st.config['task']}`'s protocol, seed "
                f"{st.config.get('seed', 0)})."
                if st.config.get("task")
                else "."
            ),
            "",
            "### How it was made",
            "",
            *_made(st),
            "",
        ]
    lines += ["## Columns", "", "| column | type | meaning |", "| --- | --- | --- |"]
    lines += [f"| `{a}` | {b} | {c} |" for a, b, c in COLUMNS]
    lines += [
        "",
        "## Loading",
        "",
        "Read the files themselves (set `folder` to this folder's path):",
        "",
        *load_snippet(infos),
        "",
        "`datasets.load_dataset(folder)` reads them too, through this card's `configs`; its "
        "cache is keyed by the folder's name and this card's YAML, which names each "
        "configuration's content (`description`: the files' SHA-256, the configuration hash, "
        "the slide code, the split sizes), so another export in a folder of the same name is "
        "not served from this one's cache. `croissant.json` describes the same files in "
        "Croissant (`mlcroissant.Dataset`).",
        "",
        "## License",
        "",
        (
            "The recordings keep the license of their original release: see "
            f"{(st0.meta.get('dataset_meta') or {}).get('source', 'the source')}."
            if data.license == "other"
            else f"{SIM_LICENSE.upper()} (the slides are the simulator's output)."
        ),
        "",
        "## Citation",
        "",
        "```bibtex",
        CITATION.replace("VERSION", version),
        "```",
        "",
    ]
    return "\n".join(lines)


def croissant_metadata(infos: list[dict], root: Path, version: str) -> dict:
    """The export's Croissant metadata (JSON-LD), built with ``mlcroissant``: one FileSet and
    one RecordSet per configuration and split, fields read from the Parquet columns."""
    mlc = require("mlcroissant", "hub")
    data = card_data(infos, version)
    distribution, record_sets = [], []
    for i in infos:
        t, c = i["shape"]
        for side in i["splits"]:
            sid = f"{i['config']}-{side}"
            distribution.append(
                mlc.FileSet(
                    id=f"parquet-{sid}",
                    name=f"parquet-{sid}",
                    description=f"the {side} split of configuration {i['config']}",
                    encoding_formats=["application/x-parquet"],
                    includes=[f"data/{i['config']}/{side}-*.parquet"],
                )
            )
            record_sets.append(
                mlc.RecordSet(
                    id=sid,
                    name=sid,
                    description=f"one record per slide ({side} split of {i['config']})",
                    fields=[_field(mlc, sid, name, fmt, desc, t, c) for name, fmt, desc in COLUMNS],
                )
            )
    meta = mlc.Metadata(
        name=data.pretty_name,
        description=f"Tactile slides (sim_tactile {version}): "
        + "; ".join(f"{i['config']}: {len(i['store'])} slides" for i in infos),
        license=["https://creativecommons.org/licenses/by/4.0/"]
        if data.license == SIM_LICENSE
        else ["other: the original release's"],
        url="https://pypi.org/project/sim-tactile/",
        version=version,
        cite_as=CITATION.replace("VERSION", version),
        keywords=list(data.tags),
        distribution=distribution,
        record_sets=record_sets,
    )
    return json.loads(json.dumps(meta.to_json(), default=str))


def _field(mlc, sid: str, name: str, fmt: str, desc: str, t: int, c: int):
    types = {"data": mlc.DataType.FLOAT32, "seed": mlc.DataType.INTEGER}
    dtype = types.get(name, mlc.DataType.FLOAT64 if fmt == "float64" else mlc.DataType.INTEGER)
    kw = {"is_array": True, "array_shape": f"-1,{c}"} if name == "data" else {}
    return mlc.Field(
        id=f"{sid}/{name}",
        name=name,
        description=desc,
        data_types=[dtype],
        source=mlc.Source(file_set=f"parquet-{sid}", extract=mlc.Extract(column=name)),
        **kw,
    )
