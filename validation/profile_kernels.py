#!/usr/bin/env python3
"""
What the LLVM kernel of ``sample()`` is made of, for cooktorrance (Smith) and roughconductor
with the same sampler: DrJit's kernel history gives each kernel's execution time and its LLVM
IR, in which the script counts the operations (divisions apart: their throughput limits these
kernels). The profile behind the "Sampling strategies" section of ``mi-brdfs bench``.

    python validation/profile_kernels.py            # 2e6 samples, 15 interleaved repeats
    python validation/profile_kernels.py --quick    # a smoke run (the test suite runs this)

It asserts nothing; run it on a quiet machine.
"""

from __future__ import annotations

import argparse
import math
import re
import statistics
from collections import Counter

import mi_brdfs  # first: it chooses the libLLVM before drjit loads




def ops(ir: str) -> Counter:
    """LLVM IR instructions and intrinsic calls of a kernel, by name."""
    found = re.findall(r"= (fdiv|fmul|fadd|fsub|fcmp|select|call [^@]*@([\w.]+))", ir)
    return Counter(re.sub(r"^llvm\.(x86\.avx\.)?", "", call).split(".")[0] if call else op
                   for op, call in found)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="a smoke run: 1e4 samples, 2 repeats")
    args = p.parse_args(argv)
    mi_brdfs.use_variant("llvm_ad_rgb")
    from mi_brdfs.benchmark.strategies import LOBES, random_draws, own
    from mi_brdfs.timing import interleaved, kernel_ir, kernel_timed, traced_kernels
    from mi_brdfs.bsdfspec import load_bsdf

    # the Smith lobe of the benchmark's strategies, the plugin's and the built-in's samplers
    _, ours, builtins = next(lobe for lobe in LOBES if "Smith" in lobe[0])
    contenders = {f"{who}, {sampler}": spec for who, specs in
                  (("cooktorrance smith", ours), ("roughconductor", builtins))
                  for sampler, spec in specs.items()}
    n = 10_000 if args.quick else 2_000_000
    draws = random_draws(math.radians(45.0), n, seed=0)
    bsdfs = {k: load_bsdf(v) for k, v in contenders.items()}
    times = interleaved({k: (lambda b=b: own(b, *draws)) for k, b in bsdfs.items()},
                        repeats=2 if args.quick else 15, timer=kernel_timed)
    print(f"sample() of {n} directions at 45° incidence, llvm_ad_rgb, medians of interleaved "
          "repeats")
    print(f"{'':40s} {'kernels':>9s} {'tracing':>9s} {'ops':>5s} {'fdiv':>5s}  other")
    for name, b in bsdfs.items():
        _, history = traced_kernels(lambda b=b: own(b, *draws))
        count = Counter()
        for k in history:
            count += ops(kernel_ir(k))
        kernels = statistics.median(kt for _, kt in times[name]) * 1e3
        tracing = statistics.median(tt for tt, _ in times[name]) * 1e3
        total = sum(k.get("operation_count", 0) for k in history)
        other = ", ".join(f"{op} {c}" for op, c in count.most_common() if op != "fdiv")
        print(f"{name:40s} {kernels:7.2f} ms {tracing:6.2f} ms {total:5d} {count['fdiv']:5d}  "
              f"{other}")


if __name__ == "__main__":
    main()
