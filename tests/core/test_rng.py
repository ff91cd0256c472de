#!/usr/bin/env python3
"""core/rs_rng.h against an independent implementation of xoshiro256** (Blackman & Vigna) and
splitmix64 (Steele, Lea & Flood) in Python integers: every u64 draw bit for bit, the uniform
draws exactly, the Box-Muller normals to 1e-15; seed derivation; and the moments of 200,000
draws (uniform mean, normal mean and variance, 5 standard errors)."""
import math
import subprocess
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

M = (1 << 64) - 1
GAMMA = 0x9E3779B97F4A7C15


def mix64(z):
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M
    return z ^ (z >> 31)


def rotl(x, k):
    return ((x << k) | (x >> (64 - k))) & M


class Xoshiro:
    def __init__(self, seed):
        x = seed
        self.s = []
        for _ in range(4):
            x = (x + GAMMA) & M
            self.s.append(mix64(x))

    def u64(self):
        s = self.s
        result = (rotl((s[1] * 5) & M, 7) * 9) & M
        t = (s[1] << 17) & M
        s[2] ^= s[0]
        s[3] ^= s[1]
        s[1] ^= s[2]
        s[0] ^= s[3]
        s[2] ^= t
        s[3] = rotl(s[3], 45)
        return result

    def uniform(self):
        return (self.u64() >> 11) * 2.0 ** -53




def main():
    dump = sys.argv[1]
    for seed in (0, 1, 42, 20261122, M):
        out = subprocess.run([dump, str(seed), "1000"], check=True, capture_output=True, text=True).stdout
        ref = Xoshiro(seed)
        for i, line in enumerate(out.splitlines()):
            u, x, z = line.split()
            u_ref = ref.u64()
            x_ref = ref.uniform()
            u1, u2 = 1.0 - ref.uniform(), ref.uniform()
            z_ref = math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
            check(int(u) == u_ref, f"seed {seed} draw {i}: u64 {u} vs {u_ref}")
            check(float(x) == x_ref, f"seed {seed} draw {i}: uniform {x} vs {x_ref!r}")
            check(abs(float(z) - z_ref) <= 1e-15 * max(1.0, abs(z_ref)), f"seed {seed} draw {i}: normal {z} vs {z_ref!r}")
        print(f"seed {seed}: 1000 x (u64, uniform, normal) match the reference")
    for seed in (0, 7, 12345678901234567):
        out = subprocess.run([dump, "derive", str(seed)], check=True, capture_output=True, text=True).stdout
        state = seed
        for k, line in enumerate(out.splitlines()):
            d, n = map(int, line.split())
            state = (state + GAMMA) & M
            check(d == mix64((seed + GAMMA * (k + 1)) & M), f"derive({seed}, {k}) = {d}")
            check(n == mix64(state), f"seed_next #{k} from {seed} = {n}")
    out = subprocess.run([dump, "3", "200000"], check=True, capture_output=True, text=True).stdout
    xs, zs = [], []
    for line in out.splitlines():
        _, x, z = line.split()
        xs.append(float(x))
        zs.append(float(z))
    n = len(xs)
    mu, mz = sum(xs) / n, sum(zs) / n
    vz = sum(z * z for z in zs) / n
    check(all(0 <= x < 1 for x in xs) and all(math.isfinite(z) for z in zs), "range")
    check(abs(mu - 0.5) < 5 * 0.2887 / math.sqrt(n), f"uniform mean {mu}")
    check(abs(mz) < 5 / math.sqrt(n), f"normal mean {mz}")
    check(abs(vz - 1) < 5 * math.sqrt(2.0 / n), f"normal variance {vz}")
    print(f"200000 draws: uniform mean {mu:.5f}, normal mean {mz:.5f}, variance {vz:.5f}")
    finish("test_rng")


if __name__ == "__main__":
    main()
