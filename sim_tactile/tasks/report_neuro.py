"""The report's neuromorphic table: for each row whose model spikes or whose input is an
encoding, the encoder's spikes per second of input and the spiking model's NeuroBench
figures (:mod:`sim_tactile.learn.neurobench`), measured on the first repeat's test samples."""

from __future__ import annotations

from ..tables import markdown_table

HEAD = [
    "run",
    "encoder spikes/s",
    "footprint [B]",
    "parameters",
    "connection sparsity",
    "activation sparsity",
    "ACs / sample",
    "MACs / sample",
    "dense ops / sample",
]


def _cells(label: str, fig: dict) -> list[str]:
    enc = fig.get("encoder") or {}
    ops = fig.get("synaptic_operations") or {}

    def num(v, fmt: str) -> str:
        return "-" if v is None else format(v, fmt)

    return [
        label,
        num(enc.get("spikes_per_s"), ".1f"),
        num(fig.get("footprint_bytes"), "d"),
        num(fig.get("parameter_count"), "d"),
        num(fig.get("connection_sparsity"), ".3f"),
        num(fig.get("activation_sparsity"), ".3f"),
        num(ops.get("effective_acs"), ".4g"),
        num(ops.get("effective_macs"), ".4g"),
        num(ops.get("dense"), ".4g"),
    ]


def neuromorphic_table(rows) -> list[str]:
    """Markdown lines of the table ([] when no row has neuromorphic figures)."""
    body = [_cells(r.label, r.extra["neuromorphic"]) for r in rows if r.extra.get("neuromorphic")]
    if not body:
        return []
    return [
        "",
        "## Neuromorphic figures",
        "",
        "NeuroBench's metrics of the spiking models and the encoders' spike rates (spikes per "
        "second of input, all channels), on the first repeat's test samples.",
        "",
        *markdown_table(HEAD, body),
    ]
