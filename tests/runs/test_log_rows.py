"""The run logs' block writers (``CsvLog.rows``, ``TumLog.rows``, used by the batched drives)
write the bytes of one ``row`` call a sample, over any numbers (signed zeros, huge, tiny,
non-finite) and any quaternion (unnormalised, zero)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from marsscene.runs.logs import CsvLog, TumLog

_FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)
_TIMES = st.floats(0.0, 1e5, allow_nan=False)


def _both(tmp: Path, make, one, block) -> tuple[bytes, bytes]:  # type: ignore[no-untyped-def]
    a, b = make(tmp / "one"), make(tmp / "block")
    one(a)
    block(b)
    a.close()
    b.close()
    return (tmp / "one").read_bytes(), (tmp / "block").read_bytes()


@settings(max_examples=60, deadline=None)
@given(values=arrays(np.float64, st.tuples(st.integers(0, 6), st.integers(1, 7)),
                     elements=_FLOATS | st.sampled_from([-0.0, 0.0, 1e-300, -1e300])),
       t0=_TIMES)
def test_csv_rows_are_row_bytes(tmp_path_factory, values: np.ndarray, t0: float) -> None:  # type: ignore[no-untyped-def]
    tmp = tmp_path_factory.mktemp("csv")
    t = t0 + 0.01 * np.arange(len(values))
    cols = ["t", *[f"c{j}" for j in range(values.shape[1])]]
    one, block = _both(tmp, lambda p: CsvLog(p, cols),
                       lambda log: [log.row(float(ti), r) for ti, r in zip(t, values, strict=True)],
                       lambda log: log.rows(t, values))
    assert one == block
    if len(values):
        assert block.count(b"\n") == len(values) + 1 and b",-0," not in block + b","


@settings(max_examples=60, deadline=None)
@given(xyz=arrays(np.float64, st.tuples(st.integers(0, 6), st.just(3)),
                  elements=st.floats(-1e4, 1e4) | st.just(-0.0)),
       quat=st.lists(st.lists(st.floats(-2.0, 2.0) | st.just(-0.0), min_size=4, max_size=4),
                     min_size=6, max_size=6),
       t0=_TIMES)
def test_tum_rows_are_row_bytes(tmp_path_factory, xyz: np.ndarray, quat: list, t0: float) -> None:  # type: ignore[no-untyped-def]
    tmp = tmp_path_factory.mktemp("tum")
    q = np.array(quat)[: len(xyz)]
    q[0 if len(q) else slice(0)] = 0.0  # a zero quaternion is written as given
    t = t0 + 0.02 * np.arange(len(xyz))
    rows = list(zip(t, xyz, q, strict=True))
    one, block = _both(tmp, lambda p: TumLog(p, "a header"),
                       lambda log: [log.row(float(ti), p, qi) for ti, p, qi in rows],
                       lambda log: log.rows(t, xyz, q))
    assert one == block
    assert b"-0.000000000 " not in block
