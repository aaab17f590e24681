"""Rows of a run's table that a reader should not take at face value, each with a sentence
that says why and what to try: a model whose accuracy is the same on every random split
(it answers alike whatever it is trained on), and an encoder that makes almost no spikes
(a spiking row then classifies silence). The run's table marks such a row with ``!`` and
the report lists the sentences under it (``ResultRow.extra["flags"]``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

#: Fewest repeats over which one accuracy on every split is taken as a sign, not chance (two
#: splits of 14 test slides agree by chance often; five rarely).
SAME_ON_EVERY_SPLIT_FROM = 5
#: Spikes per channel per slide below which an encoder is called silent: under one spike a
#: channel cannot carry the texture (finger7-v1's SA Izhikevich encoder makes 2.4; a default
#: LIF encoder on it 0.29, and its row scored 0.286 on 7 classes).
SILENT_SPIKES_PER_CHANNEL = 1.0


def row_flags(accuracies: Sequence[float], neuromorphic: dict | None, window_s: float) -> list[str]:
    """The sentences for one row: its ``accuracies`` over the repeats, its neuromorphic
    figures (the encoder's spike rate, :func:`~sim_tactile.learn.neurobench.encoder_rate`)
    and the length of a slide [s]."""
    out = []
    acc = [float(a) for a in accuracies]
    if len(acc) >= SAME_ON_EVERY_SPLIT_FROM and max(acc) == min(acc) < 1.0:
        out.append(
            f"the same accuracy ({acc[0]:.3f}) on all {len(acc)} random splits, so its SD of "
            "0 measures nothing: the model decides alike whatever it is trained on (one "
            "answer for all, or input that tells some classes apart and the others not at "
            "all); check its settings and its input"
        )
    enc = (neuromorphic or {}).get("encoder") or {}
    rate = enc.get("spikes_per_s_per_channel")
    if rate is not None and window_s > 0 and rate * window_s < SILENT_SPIKES_PER_CHANNEL:
        out.append(
            f"the encoder makes {rate * window_s:.2g} spikes per channel per slide (under "
            f"{SILENT_SPIKES_PER_CHANNEL:g}): too few to tell the textures apart; raise its "
            "gain or lower its threshold"
        )
    return out


def flag_rows(rows, window_s: float, log: Callable[[str], None]) -> None:
    """Put each doubtful row's sentences in its ``extra["flags"]`` and log them
    (``rows``: :class:`~.report.ResultRow` s)."""
    for row in rows:
        said = row_flags(row.extra.get("accuracies", ()), row.extra.get("neuromorphic"), window_s)
        if said:
            row.extra["flags"] = said
            log(f"{row.label}: check this row: {'; '.join(said)}")
