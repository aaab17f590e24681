"""Fuzzing a small store (2 plates x 3 slides, made without physics): a flipped bit, a
truncation or a removal anywhere in any of its files (chunks and ``zarr.json`` files alike)
is either refused with a StoreError (or ConfigError) or read back exactly equal to the
original, by every reader; never read as other values, never another exception. Every
single-bit flip of the index arrays' chunks is found (exhaustively), and ``--resume`` after
any fault either refuses or restores the store bit for bit. The fast lane samples; the
slow lane searches wider and exhausts the index chunks."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from _stores import assert_same, make_store, quiet_generate, read_back, store_files
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sim_tactile import datasets
from sim_tactile.datasets.integrity import INDEX_DTYPES
from sim_tactile.errors import ConfigError, StoreError

_SETTINGS = {
    "deadline": None,
    "derandomize": True,  # the same cases on every run: a failure is reproducible
    "suppress_health_check": [HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
}


@pytest.fixture(scope="module")
def ref(tmp_path_factory) -> Path:
    return make_store(tmp_path_factory.mktemp("fuzz"))


@pytest.fixture(scope="module")
def ref_back(ref) -> dict:
    return read_back(ref)


@pytest.fixture(scope="module")
def work(ref, tmp_path_factory) -> Path:
    """A copy of the reference store; each case damages one file and puts it back."""
    out = tmp_path_factory.mktemp("work") / "s.zarr"
    shutil.copytree(ref, out)
    return out


@st.composite
def faults(draw, files: list[Path], ref: Path):
    """``(file, kind, position)``: a bit to flip, a length to truncate to, or a removal."""
    rel = draw(st.sampled_from(files))
    size = (ref / rel).stat().st_size
    kind = draw(st.sampled_from(["flip", "flip", "flip", "truncate", "remove"]))
    if kind == "flip":
        return rel, kind, draw(st.integers(0, 8 * size - 1))
    if kind == "truncate":
        return rel, kind, draw(st.integers(0, size - 1))
    return rel, kind, 0


def _apply(path: Path, kind: str, pos: int) -> None:
    if kind == "remove":
        path.unlink()
        return
    b = bytearray(path.read_bytes())
    if kind == "flip":
        b[pos // 8] ^= 1 << (pos % 8)
    else:
        del b[pos:]
    path.write_bytes(bytes(b))


def _refused_or_same(store: Path, ref_back: dict) -> str:
    try:
        got = read_back(store)
    except (StoreError, ConfigError) as exc:
        assert "\n" not in str(exc)
        return "refused"
    assert_same(got, ref_back, history=True)
    return "same"


def _check_fault(ref: Path, work: Path, ref_back: dict, fault) -> str:
    rel, kind, pos = fault
    original = (ref / rel).read_bytes()
    try:
        _apply(work / rel, kind, pos)
        return _refused_or_same(work, ref_back)
    finally:
        (work / rel).write_bytes(original)


def _fuzz(ref, work, ref_back, examples: int) -> None:
    files = store_files(ref)
    assert any("zarr.json" in str(f) for f in files) and any("/c/" in str(f) for f in files)

    @settings(max_examples=examples, **_SETTINGS)
    @given(fault=faults(files, ref))
    def case(fault):
        _check_fault(ref, work, ref_back, fault)

    case()


def test_faults_anywhere_are_refused_or_harmless(ref, work, ref_back):
    _fuzz(ref, work, ref_back, 50)


@pytest.mark.slow
def test_faults_anywhere_are_refused_or_harmless_wide(ref, work, ref_back):
    _fuzz(ref, work, ref_back, 600)


def _index_chunks(ref: Path) -> list[Path]:
    out = [f for f in store_files(ref) if f.parts[0] in INDEX_DTYPES and f.name != "zarr.json"]
    assert {f.parts[0] for f in out} == set(INDEX_DTYPES)  # every index array has a chunk
    return out


def _every_index_flip_is_found(ref: Path, work: Path, chunks: list[Path], step: int) -> dict:
    want = datasets.open(ref).index_arrays()
    seen = {"refused": 0, "same": 0}
    for rel in chunks:
        original = (ref / rel).read_bytes()
        for bit in range(0, 8 * len(original), step):
            try:
                _apply(work / rel, "flip", bit)
                got = datasets.open(work).index_arrays()
            except StoreError as exc:
                assert f"'{rel.parts[0]}'" in str(exc), (rel, bit, str(exc))
                seen["refused"] += 1
                continue
            finally:
                (work / rel).write_bytes(original)
            for k, v in want.items():
                np.testing.assert_array_equal(got[k], v, err_msg=f"{rel} bit {bit}: {k}")
            seen["same"] += 1
    return seen


def test_single_bit_flips_in_the_labels_are_found(ref, work):
    labels = [f for f in _index_chunks(ref) if f.parts[0] == "labels"]
    seen = _every_index_flip_is_found(ref, work, labels, 3)  # every 3rd bit: the slow lane has all
    assert seen == {"refused": 62, "same": 0}


@pytest.mark.slow
def test_every_single_bit_flip_in_the_index_arrays_is_found(ref, work):
    chunks = _index_chunks(ref)
    seen = _every_index_flip_is_found(ref, work, chunks, 1)
    assert seen["same"] == 0  # even a flip that would decode to the same values is found
    assert seen["refused"] == 8 * sum((ref / f).stat().st_size for f in chunks)


@pytest.mark.slow
def test_resume_after_any_fault_refuses_or_restores_the_store(ref, ref_back, tmp_path):
    """``generate --resume`` (the same configuration) after a fault anywhere: a StoreError,
    or the store read back equal to the original (its history aside)."""
    files = store_files(ref)
    cfg = ref.parent / "tiny.json"
    outcomes = {"refused": 0, "restored": 0}

    @settings(max_examples=80, **_SETTINGS)
    @given(fault=faults(files, ref))
    def case(fault):
        rel, kind, pos = fault
        out = tmp_path / "r.zarr"
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(ref, out)
        _apply(out / rel, kind, pos)
        try:
            quiet_generate(cfg, out, resume=True)
        except StoreError as exc:
            assert "\n" not in str(exc)
            outcomes["refused"] += 1
            return
        assert_same(read_back(out), ref_back)
        outcomes["restored"] += 1

    case()
    assert outcomes["restored"] > 0
