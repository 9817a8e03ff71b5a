"""glint.Volume.from_array against numpy's copies of the same array (scripts/bench/bench-from-array)."""

import os
import platform
import statistics
import sys
import time

import numpy as np

import glint


def median_s(fn, runs=5):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
        del out
    return statistics.median(times)


def main(edges):
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, numpy {np.__version__}")
    print(f"{'edge':>5} {'order':>5} {'from_array s':>13} {'np order s':>11} {'np copy s':>10} {'ratio':>6}")
    for n in edges:
        base = np.random.default_rng(1).random((n, n, n), dtype=np.float32)
        for order in ("C", "F"):
            arr = np.asarray(base, order=order)
            ours = median_s(lambda: glint.Volume.from_array(arr))
            to_f = median_s(lambda: np.array(arr, order="F"))
            plain = median_s(lambda: arr.copy(order="K"))
            print(f"{n:>5} {order:>5} {ours:>13.3f} {to_f:>11.3f} {plain:>10.3f} {ours / to_f:>6.2f}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]])
