#!/usr/bin/python3
"""The variance components' model (calib/rs_calib_vce.c) against the full adjustment, in numpy.

rs_calib_vce.c marginalises the landmarks: each pick has the 2x2 covariance its own sigma and its
survey's make. The oracle here is the textbook adjustment with the landmarks as unknowns: rows
u, v (sigma_px^2 theta_px) and E, N, U of each landmark (sigma^2 theta_h, theta_v), unknowns the
pose rt (6) and every landmark's position (3 each), Jacobians from mrcal's Python
(transform_point_rt, project with gradients), dense. For each log theta the driver printed it
computes the restricted log-likelihood -1/2 (log det Sigma + log det X'WX + e'We), q_g (the
group's sum of squared whitened residuals) and r_g (the sum of its redundancy numbers
1 - diag(H)), the Fisher information theta_g theta_h tr(P V_g P V_h) / 2 and the observed
information (minus the score's derivative, by central differences of numpy's), and checks the
driver's to 1e-6 (relative). The problem has no camera priors, so the model's linear term for
their gradient is zero here as in the driver, and the step dx from the state (the driver's
solution, not exactly a minimum) is the model's own. At the driver's posterior mode
the score (q - r)/2 - L / lp^2 puts it within 3% of a posterior 1-sigma of the exact mode. The pose's 99.9% region (rs_calib__pose_region_m2)
against scipy's F quantiles to 1e-9. Skips (77) without mrcal's Python module."""
import json
import subprocess
import sys

try:
    import numpy as np
    import mrcal
except ImportError:
    print("mrcal's Python module is missing: skipped")
    sys.exit(77)

out = subprocess.run([sys.argv[1]], check=True, capture_output=True, text=True)
if out.stderr:
    print("FAIL: the library printed:", out.stderr)
    sys.exit(1)
d = json.loads(out.stdout)
if "error" in d:
    print("FAIL: driver:", d["error"])
    sys.exit(1)

rt = np.array(d["rt"])
P = np.array(d["p"]).reshape(-1, 3)
S = np.array(d["sigma_enu"]).reshape(-1, 3)
Q = np.array(d["q"]).reshape(-1, 2)
spx = np.array(d["sigma_px"])
N = len(P)
intr = np.array(d["intrinsics"])

# pixel, its Jacobian wrt rt (2x6) and wrt the point (2x3), at the surveyed points
pc, dpc_drt, dpc_dp = mrcal.transform_point_rt(rt, P, get_gradients=True)
qp, dq_dpc, _ = mrcal.project(pc, d["lensmodel"], intr, get_gradients=True)
G = np.einsum("nij,njk->nik", dq_dpc, dpc_drt)
J = np.einsum("nij,njk->nik", dq_dpc, dpc_dp)
e_pix = qp - Q

# the full model: rows (2 pixel + 3 survey) per landmark; columns 6 + 3N
nr, nc = 5 * N, 6 + 3 * N
X = np.zeros((nr, nc))
e = np.zeros(nr)
var0 = np.zeros(nr)
group = np.zeros(nr, dtype=int)
for i in range(N):
    r0 = 5 * i
    X[r0:r0 + 2, :6] = G[i]
    X[r0:r0 + 2, 6 + 3 * i:9 + 3 * i] = J[i]
    e[r0:r0 + 2] = e_pix[i]
    var0[r0:r0 + 2] = spx[i] ** 2
    for a in range(3):
        X[r0 + 2 + a, 6 + 3 * i + a] = 1.0  # survey residual p - p_survey = dp (0 at the start)
        var0[r0 + 2 + a] = S[i, a] ** 2
        group[r0 + 2 + a] = 1 if a < 2 else 2


def model(L):
    var = var0 * np.exp(np.asarray(L)[group])
    W = 1.0 / var
    return var, W


gamma = np.zeros(6)  # the camera priors' gradient: this problem has none


def full(L):
    var, W = model(L)
    A = X.T @ (W[:, None] * X)
    b = X.T @ (W * e)
    b[:6] += gamma
    dx = -np.linalg.solve(A, b)
    eh = e + X @ dx
    quad = eh @ (W * eh) + 2 * gamma @ dx[:6]
    ll = -0.5 * (np.sum(np.log(var)) + np.linalg.slogdet(A)[1] + quad)
    H = X @ np.linalg.solve(A, X.T * W[None, :])  # hat matrix of the whitened model
    red = 1.0 - np.diag(H)
    th = np.exp(np.asarray(L))
    q = np.array([np.sum(W[group == g] * eh[group == g] ** 2) for g in range(3)])
    r = np.array([np.sum(red[group == g]) for g in range(3)])
    Pm = np.diag(W) - (W[:, None] * X) @ np.linalg.solve(A, X.T * W[None, :])
    Vg = [np.diag(np.where(group == g, var, 0.0)) for g in range(3)]  # theta_g V_g
    F = np.array([[0.5 * np.trace(Pm @ Vg[g] @ Pm @ Vg[h]) for h in range(3)] for g in range(3)])
    return ll, q, r, F


fails = 0


def close(a, b, tol, what):
    global fails
    a, b = np.asarray(a, float), np.asarray(b, float)
    err = np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b)))
    ok = err <= tol
    print(f"  {what}: {'ok' if ok else 'FAIL'} (largest relative difference {err:.2e})")
    if not ok:
        print(f"    driver {a}\n    numpy  {b}")
        fails += 1


for ev in d["evaluations"]:
    ll, q, r, F = full(ev["L"])
    print(f"log theta {ev['L']}:")
    close(ev["loglik"], ll, 1e-6, "restricted log-likelihood")
    close(ev["q"], q, 1e-6, "q (squared whitened residuals per group)")
    close(ev["r"], r, 1e-6, "r (redundancy per group)")
    close(np.array(ev["F"]).reshape(3, 3), F, 1e-6, "Fisher information")
    # the observed information: minus the derivative of the score (q - r) / 2, by central
    # differences of numpy's (step 1e-5 in log theta: truncation ~1e-10, rounding ~1e-9)
    O = np.zeros((3, 3))
    for h in range(3):
        Lp, Lm_ = np.array(ev["L"], float), np.array(ev["L"], float)
        Lp[h] += 1e-5
        Lm_[h] -= 1e-5
        _, qp, rp, _ = full(Lp)
        _, qm, rm, _ = full(Lm_)
        O[:, h] = -0.5 * ((qp - rp) - (qm - rm)) / 2e-5
    close(np.array(ev["O"]).reshape(3, 3), O, 1e-5, "observed information (central differences)")

lp = 2 * np.log(d["prior_factor"])
Lm = np.array(d["mode"])
_, q, r, Fm = full(Lm)
score = 0.5 * (q - r) - Lm / lp ** 2
# the distance to the exact mode, one Newton step with the posterior information F + 1/lp^2, in
# posterior 1-sigmas: the driver stops when a step is below 1% of that 1-sigma (Fisher scoring
# converges linearly, so a few % may remain)
H = Fm + np.eye(3) / lp ** 2
dist = np.abs(np.linalg.solve(H, score)) / np.sqrt(np.diag(np.linalg.inv(H)))
print(f"posterior mode {Lm}: score {score}, {np.max(dist):.4f} posterior sigma from the exact mode")
if np.max(dist) > 0.03:
    print("FAIL: the driver's mode is not the posterior mode (to 3% of its 1-sigma)")
    fails += 1
# the pose's confidence region: 6 F(6, nu; 1 - alpha) / kappa, chi-square 6 dof for nu infinite;
# the oracle is scipy's F and chi-square quantiles (python3-scipy comes with python3-mrcal)
try:
    from scipy import stats
except ImportError:
    stats = None
    print("scipy is missing: the confidence regions are not checked")
for alpha, nu, kappa, got in d.get("regions", []) if stats else []:
    if nu >= 1e300:
        want = stats.chi2.ppf(1 - alpha, 6) / kappa
    else:
        want = 6 * stats.f.ppf(1 - alpha, 6, nu) / kappa
    ok = abs(got - want) <= 1e-9 * want
    print(f"  region alpha {alpha} nu {nu:g} kappa {kappa}: {got:.10g} (scipy {want:.10g}) {'ok' if ok else 'FAIL'}")
    fails += not ok
if stats and len(d.get("regions", [])) < 10:
    print("FAIL: the driver printed no confidence regions")
    fails += 1
print("all passed" if not fails else f"{fails} failure(s)")
sys.exit(1 if fails else 0)
