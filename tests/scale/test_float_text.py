"""The compiled float text (Schubfach) against Python's ``repr``, the text
json and csv write: every float's shortest round-trip digits, nearest the
float, in repr's layout."""

import numpy as np
import pytest

pytest.importorskip("numba")

from isoflow.scale.float_text import FLOAT_WIDTH, power_table, shortest_cells  # noqa: E402

SMALLEST_NORMAL = 2.2250738585072014e-308


def texts(values: np.ndarray) -> list[str | None]:
    """What the compiled writer gives per value (None: left to the caller)."""
    chars = np.zeros((len(values), FLOAT_WIDTH), np.uint8)
    lengths = np.full(len(values), -1, np.int64)
    shortest_cells(np.ascontiguousarray(values, np.float64).view(np.uint64), power_table(), chars, lengths)
    return [bytes(row[FLOAT_WIDTH - n:]).decode() if n else None for row, n in zip(chars, lengths)]


def assert_as_repr(values: np.ndarray) -> None:
    got = texts(values)
    wrong = [(repr(v), g) for v, g in zip(values.tolist(), got)
             if g != (repr(v) if np.isfinite(v) and (v == 0 or abs(v) >= SMALLEST_NORMAL) else None)]
    assert not wrong, f"{len(wrong)} of {len(values)} differ, e.g. {wrong[:5]}"


def test_random_bit_patterns_every_exponent(rng):
    # uniform over the bits: every exponent, sign, NaNs and subnormals among them
    assert_as_repr(rng.integers(0, 2**64, 200_000, dtype=np.uint64, endpoint=False).view(np.float64))


def test_measures_as_a_table_holds_them(rng):
    # centroids and world volumes: sums over counts, plus a half, times a pitch
    sums, counts = rng.integers(0, 10**9, 200_000), rng.integers(1, 10**5, 200_000)
    assert_as_repr((sums / counts + 0.5) * rng.choice([1.0, 0.1, 0.35, 2.5e-3], 200_000))


def test_where_the_layout_and_the_interval_change():
    # powers of two (the interval below is half as wide), powers of ten and
    # their neighbours (digit counts change), the layout's ends (1e-4 is
    # positional, 1e-5 not; 1e16 takes an exponent), the largest and the
    # smallest normal, whole numbers around 2^53, signed zeros
    pow2 = [2.0**e for e in range(-1022, 1024)]
    pow10 = [float(f"1e{e}") for e in range(-307, 309)]
    near = np.array(pow2 + pow10)
    values = np.concatenate([near, np.nextafter(near, 0), np.nextafter(near, np.inf), -near,
                             [0.0, -0.0, 1e-4, 9.999999999999999e-05, 1e-05, 1e16, 9999999999999998.0,
                              2.0**53 + 2, 123456789012345678.0, 0.1, 0.3, 1 / 3, 2e23, 1e23,
                              1.7976931348623157e308, SMALLEST_NORMAL]])
    assert_as_repr(values[np.isfinite(values)])


def test_left_to_the_caller():
    assert texts(np.array([np.nan, np.inf, -np.inf, 5e-324, -SMALLEST_NORMAL / 2])) == [None] * 5
