#!/usr/bin/env python3
"""roadside eval --tracks (eval/mot/rs_mot.h) against a plain Python implementation of the papers'
definitions written here: CLEAR MOT (Bernardin and Stiefelhagen 2008) with scipy's
linear_sum_assignment, IDF1 (Ristani et al. 2016) as the (G+T)x(G+T) assignment of the paper
(not the reduced one roadside solves), HOTA (Luiten et al. 2021) as TrackEval's HOTA.py computes
it with the similarity max(0, 1 - d/D), the position RMSE, NEES and the crossings. Hand-computed
cases (perfect tracks, one id switch, all missed, false positives), random small cases (seed
printed), and bad input. Usage: test_mot_metrics.py [NRANDOM]."""
import json
import math
import os
import random
import subprocess
import sys
import tempfile

import numpy as np

try:
    from scipy.optimize import linear_sum_assignment
except ImportError:  # pragma: no cover
    print("scipy missing: skipped")
    sys.exit(77)

ROADSIDE = os.environ.get("ROADSIDE")
if not ROADSIDE or not os.path.exists(ROADSIDE):
    print("ROADSIDE not set or missing: skipped")
    sys.exit(77)

GT_HEADER = "time_s,vehicle_id,class,e_m,n_m,speed_mps,heading_deg,cameras"
TR_HEADER = ("time_s,track_id,e_m,n_m,lat_deg,lon_deg,speed_mps,heading_deg,sigma_e_m,sigma_n_m,cov_en_m2,"
             "sigma_speed_mps,sigma_heading_deg,age_s,detections,cameras")
FAILS = []


def check(cond, msg):
    if not cond:
        FAILS.append(msg)
        print("FAIL:", msg)


def write_case(d, gt, tr):
    """gt: rows (t, vid, e, n, cams list); tr: rows (t, tid, e, n, se, sn, c). Returns the paths."""
    g, h = os.path.join(d, "gt.csv"), os.path.join(d, "tracks.csv")
    with open(g, "w") as f:
        f.write(GT_HEADER + "\n")
        for t, vid, e, n, cams in gt:
            f.write(f"{t!r},{vid},sedan,{e!r},{n!r},0,0,{'+'.join(cams)}\n")
    with open(h, "w") as f:
        f.write(TR_HEADER + "\n")
        for t, tid, e, n, se, sn, c in tr:
            f.write(f"{t!r},{tid},{e!r},{n!r},,,,,{se!r},{sn!r},{c!r},,,,,\n")
    return g, h


def run(d, gt, tr, *extra):
    g, h = write_case(d, gt, tr)
    out = os.path.join(d, "m.json")
    p = subprocess.run([ROADSIDE, "eval", "--tracks", h, "--gt-tracks", g, "-o", out, *extra],
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"roadside eval failed: {p.stderr}")
    with open(out) as f:
        return json.load(f)


# ---- the oracle ----

def oracle(gt, tr, D=2.0, all_gt=False):
    steps = sorted({r[0] for r in gt})
    G = {s: sorted([r for r in gt if r[0] == s], key=lambda r: r[1]) for s in steps}
    H = {s: sorted([r for r in tr if r[0] == s], key=lambda r: r[1]) for s in steps}
    dist = lambda g, h: math.hypot(h[2] - g[2], h[3] - g[3])
    BIG = 1e9

    def assign(A, B):
        """Most pairs closer than D, then the least sum: {i: j}."""
        if not A or not B:
            return {}
        C = np.array([[dist(a, b) if dist(a, b) < D else BIG for b in B] for a in A])
        r, c = linear_sum_assignment(C)
        return {i: j for i, j in zip(r, c) if C[i, j] < BIG}

    # the rows counted at each step (ignore rule: unmatched tracks within D of an unseen vehicle)
    CG, CH, ignored = {}, {}, 0
    for s in steps:
        cg = [g for g in G[s] if all_gt or g[4]]
        un = [g for g in G[s] if not (all_gt or g[4])]
        m = assign(cg, H[s])
        matched = set(m.values())
        ch = [h for j, h in enumerate(H[s]) if j in matched or not any(dist(u, h) < D for u in un)]
        ignored += len(H[s]) - len(ch)
        CG[s], CH[s] = cg, ch
    # CLEAR MOT
    M, last, gap = {}, {}, {}
    fp = fn = idsw = frag = matches = 0
    sum_d = sum_d2 = sum_tr = sum_nees = 0.0
    n_tr = n_nees = 0
    ref, pending, before = {}, {}, {}
    crossings = kept = 0
    for s in steps:
        cg, ch = CG[s], CH[s]
        pairs = {}
        used = set()
        for i, g in enumerate(cg):
            if g[1] in M:
                for j, h in enumerate(ch):
                    if h[1] == M[g[1]] and j not in used and dist(g, h) < D:
                        pairs[i] = j
                        used.add(j)
                        break
        ri = [i for i in range(len(cg)) if i not in pairs]
        cj = [j for j in range(len(ch)) if j not in used]
        sub = assign([cg[i] for i in ri], [ch[j] for j in cj])
        for a, b in sub.items():
            pairs[ri[a]] = cj[b]
        fp += len(ch) - len(pairs)
        for i, g in enumerate(cg):
            vid = g[1]
            h = ch[pairs[i]][1] if i in pairs else None
            cams = set(g[4])
            if cams:  # crossings
                if vid not in ref:
                    ref[vid] = cams
                elif not (cams & ref[vid]):
                    crossings += 1
                    pending[vid] = True
                    before[vid] = M.get(vid)
                    ref[vid] = cams
            if h is not None and pending.get(vid):
                kept += before[vid] is not None and before[vid] == h
                pending[vid] = False
            if h is None:
                fn += 1
                if vid in M:
                    gap[vid] = True
                continue
            matches += 1
            if vid in M and M[vid] != h:
                idsw += 1
            if gap.get(vid):
                frag += 1
            gap[vid] = False
            M[vid] = h
            hr = ch[pairs[i]]
            de, dn = hr[2] - g[2], hr[3] - g[3]
            sum_d += math.hypot(de, dn)
            sum_d2 += de * de + dn * dn
            C = np.array([[hr[4] ** 2, hr[6]], [hr[6], hr[5] ** 2]])
            sum_tr += C[0, 0] + C[1, 1]
            n_tr += 1
            if C[0, 0] > 0 and np.linalg.det(C) > 0:
                dv = np.array([de, dn])
                sum_nees += dv @ np.linalg.solve(C, dv)
                n_nees += 1
    Ngt = sum(len(CG[s]) for s in steps)
    Nhyp = sum(len(CH[s]) for s in steps)
    res = {"MOTA": 1 - (fn + fp + idsw) / Ngt, "FP": fp, "FN": fn, "IDSW": idsw, "Frag": frag, "matches": matches,
           "MOTP_m": sum_d / matches if matches else None, "rmse_m": math.sqrt(sum_d2 / matches) if matches else None,
           "predicted_rms_m": math.sqrt(sum_tr / n_tr) if n_tr else None,
           "NEES": sum_nees / n_nees if n_nees else None, "num_gt": Ngt, "num_hyp": Nhyp, "ignored": ignored,
           "crossings": {"count": crossings, "kept": kept, "share": kept / crossings if crossings else None}}
    # IDF1: Ristani et al.'s bipartite graph with the unmatched costs, (V+T) x (V+T)
    vids = sorted({g[1] for s in steps for g in CG[s]})
    tids = sorted({h[1] for s in steps for h in CH[s]})
    V, T = len(vids), len(tids)
    glen = {v: 0 for v in vids}
    tlen = {t: 0 for t in tids}
    ov = np.zeros((V, T))
    for s in steps:
        for g in CG[s]:
            glen[g[1]] += 1
            for h in CH[s]:
                if dist(g, h) < D:
                    ov[vids.index(g[1]), tids.index(h[1])] += 1
        for h in CH[s]:
            tlen[h[1]] += 1
    n = V + T
    big = 1e9
    C = np.full((n, n), big)
    C[V:, T:] = 0
    for i, v in enumerate(vids):
        C[i, T + i] = glen[v]  # vehicle unmatched: its rows are IDFN
        for j, t in enumerate(tids):
            C[i, j] = glen[v] + tlen[t] - 2 * ov[i, j]
    for j, t in enumerate(tids):
        C[V + j, j] = tlen[t]  # track unmatched: IDFP
    r, c = linear_sum_assignment(C)
    idtp = sum(ov[i, j] for i, j in zip(r, c) if i < V and j < T)
    res.update({"IDTP": idtp, "IDF1": 2 * idtp / (Ngt + Nhyp), "IDFP": Nhyp - idtp, "IDFN": Ngt - idtp})
    # HOTA, as TrackEval's HOTA.py
    alphas = np.arange(0.05, 0.99, 0.05)
    eps = np.finfo("float").eps
    pmc = np.zeros((V, T))
    gcount = np.zeros((V, 1))
    tcount = np.zeros((1, T))
    sims = {}
    for s in steps:
        gi = np.array([vids.index(g[1]) for g in CG[s]], dtype=int)
        ti = np.array([tids.index(h[1]) for h in CH[s]], dtype=int)
        S = np.array([[max(0.0, 1 - dist(g, h) / D) for h in CH[s]] for g in CG[s]]).reshape(len(gi), len(ti))
        sims[s] = (gi, ti, S)
        den = S.sum(0)[np.newaxis, :] + S.sum(1)[:, np.newaxis] - S
        sim_iou = np.zeros_like(S)
        mask = den > 0 + eps
        sim_iou[mask] = S[mask] / den[mask]
        pmc[gi[:, np.newaxis], ti[np.newaxis, :]] += sim_iou
        gcount[gi] += 1
        tcount[0, ti] += 1
    align = pmc / (gcount + tcount - pmc)
    TP, FN, FP, LOC = (np.zeros(len(alphas)) for _ in range(4))
    mc = [np.zeros((V, T)) for _ in alphas]
    for s in steps:
        gi, ti, S = sims[s]
        if len(gi) == 0:
            FP += len(ti)
            continue
        if len(ti) == 0:
            FN += len(gi)
            continue
        score = align[gi[:, np.newaxis], ti[np.newaxis, :]] * S
        rr, cc = linear_sum_assignment(-score)
        for a, alpha in enumerate(alphas):
            ok = S[rr, cc] >= alpha - eps
            k = int(ok.sum())
            TP[a] += k
            FN[a] += len(gi) - k
            FP[a] += len(ti) - k
            if k:
                LOC[a] += S[rr[ok], cc[ok]].sum()
                mc[a][gi[rr[ok]], ti[cc[ok]]] += 1
    assa = np.zeros(len(alphas))
    for a in range(len(alphas)):
        m = mc[a]
        assa[a] = np.sum(m * (m / np.maximum(1, gcount + tcount - m))) / max(1, TP[a])
    deta = TP / np.maximum(1, TP + FN + FP)
    loca = np.maximum(1e-10, LOC) / np.maximum(1e-10, TP)
    res.update({"HOTA": float(np.mean(np.sqrt(deta * assa))), "DetA": float(np.mean(deta)),
                "AssA": float(np.mean(assa)), "LocA": float(np.mean(loca))})
    return res


def compare(got, want, label, tol=1e-9):
    for k, w in want.items():
        if k == "crossings":
            compare(got["crossings"], w, label + " crossings", tol)
            continue
        g = got.get(k)
        if w is None or g is None:
            check(w is None and g is None, f"{label}: {k}: roadside {g}, oracle {w}")
        else:
            check(abs(g - w) <= tol * max(1, abs(w)), f"{label}: {k}: roadside {g}, oracle {w}")


# ---- cases ----

def random_case(rng):
    """Vehicles on straight lines, tracks near them with switches, gaps and false positives."""
    Nsteps = rng.randint(3, 9)
    cams_all = ["c1", "c2", "c3"]
    vehicles = []
    for v in range(rng.randint(1, 6)):
        vehicles.append((f"v{v}", rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(-3, 3), rng.uniform(-3, 3),
                         rng.randint(0, Nsteps - 1), rng.randint(1, Nsteps)))
    gt, tr = [], []
    tid_of = {v[0]: rng.randint(1, 4) for v in vehicles}
    for s in range(Nsteps):
        t = 100 + 0.1 * s
        for vid, e0, n0, ve, vn, start, life in vehicles:
            if not (start <= s < start + life):
                continue
            e, n = e0 + ve * s, n0 + vn * s
            cams = sorted(rng.sample(cams_all, rng.randint(0, 2)))
            gt.append((t, vid, e, n, cams))
            if rng.random() < 0.15:
                continue  # missed
            if rng.random() < 0.1:
                tid_of[vid] = rng.randint(1, 9)  # an id switch
            se, sn = rng.uniform(0.1, 1), rng.uniform(0.1, 1)
            c = rng.uniform(-0.5, 0.5) * se * sn
            tr.append((t, f"t{tid_of[vid]}_{vid}" if rng.random() < 0.8 else f"t{tid_of[vid]}",
                       e + rng.gauss(0, 0.7), n + rng.gauss(0, 0.7), se, sn, c))
        for _ in range(rng.randint(0, 2)):  # false positives
            tr.append((t, f"fp{rng.randint(0, 3)}", rng.uniform(-20, 20), rng.uniform(-20, 20), 0.5, 0.5, 0.0))
    # a track id at most once per step
    seen, tr2 = set(), []
    for r in tr:
        if (r[0], r[1]) not in seen:
            seen.add((r[0], r[1]))
            tr2.append(r)
    if not any(g[4] for g in gt):
        gt[0] = gt[0][:4] + (["c1"],)
    return gt, tr2


def hand_cases(d):
    # two vehicles, 4 steps, perfect tracks
    gt = [(float(s), v, 10.0 * i + s, 0.0, ["c1"]) for s in range(4) for i, v in enumerate(["a", "b"])]
    tr = [(g[0], "T" + g[1], g[2], g[3], 0.5, 0.5, 0.0) for g in gt]
    r = run(d, gt, tr)
    for k in ("MOTA", "IDF1", "HOTA", "DetA", "AssA", "LocA"):
        check(r[k] == 1, f"perfect tracks: {k} = {r[k]}, expected 1")
    check(r["FP"] == r["FN"] == r["IDSW"] == 0 and r["MOTP_m"] == 0, f"perfect tracks: {r}")
    # one id switch: a is tracked by 1 for two steps then by 2: IDSW 1, MOTA 1 - 1/8, IDTP 6 of 8
    tr_sw = [(g[0], ("T1" if g[0] < 2 else "T2") if g[1] == "a" else "Tb", g[2], g[3], 0.5, 0.5, 0.0) for g in gt]
    r = run(d, gt, tr_sw)
    check(r["IDSW"] == 1 and abs(r["MOTA"] - (1 - 1 / 8)) < 1e-12, f"one switch: IDSW {r['IDSW']} MOTA {r['MOTA']}")
    check(abs(r["IDF1"] - 6 / 8) < 1e-12, f"one switch: IDF1 {r['IDF1']}, expected 0.75")
    # all missed: no track row at all
    r = run(d, gt, [])
    check(r["FN"] == 8 and r["MOTA"] == 0 and r["IDF1"] == 0 and r["HOTA"] == 0, f"all missed: {r}")
    # false positives: the perfect tracks plus 3 far-away rows: FP 3, MOTA 1 - 3/8, IDF1 2*8/19
    fps = [(float(s), "F", 500.0, 500.0, 1.0, 1.0, 0.0) for s in range(3)]
    r = run(d, gt, tr + fps)
    check(r["FP"] == 3 and abs(r["MOTA"] - (1 - 3 / 8)) < 1e-12, f"false positives: FP {r['FP']} MOTA {r['MOTA']}")
    check(abs(r["IDF1"] - 16 / 19) < 1e-12, f"false positives: IDF1 {r['IDF1']}, expected 16/19")
    # a crossing: a seen by c1, then c1 and c2, then c2 alone (disjoint from c1), one track: kept;
    # through a step seen by none, the same; with a new id after it: not kept; c1, c1+c2, c1: none
    gtx = [(0.0, "a", 0.0, 0.0, ["c1"]), (1.0, "a", 1.0, 0.0, ["c1", "c2"]), (2.0, "a", 2.0, 0.0, ["c2"])]
    trx = [(g[0], "T", g[2], g[3], 0.5, 0.5, 0.0) for g in gtx]
    r = run(d, gtx, trx)
    check(r["crossings"] == {"count": 1, "kept": 1, "share": 1}, f"handover through overlap: {r['crossings']}")
    r = run(d, gtx[:2] + [(2.0, "a", 2.0, 0.0, ["c1"])], trx)
    check(r["crossings"]["count"] == 0, f"back into the first view: no crossing, {r['crossings']}")
    gtx[1] = (1.0, "a", 1.0, 0.0, [])
    r = run(d, gtx, trx)
    check(r["crossings"] == {"count": 1, "kept": 1, "share": 1}, f"crossing kept: {r['crossings']}")
    r = run(d, gtx, trx[:2] + [(2.0, "U", 2.0, 0.0, 0.5, 0.5, 0.0)])
    check(r["crossings"]["kept"] == 0 and r["crossings"]["count"] == 1, f"crossing lost: {r['crossings']}")
    # NEES: errors of exactly one sigma along e on a diagonal covariance: d^T C^-1 d = 1
    gtn = [(0.0, "a", 0.0, 0.0, ["c1"])]
    r = run(d, gtn, [(0.0, "T", 0.3, 0.0, 0.3, 0.1, 0.0)])
    check(abs(r["NEES"] - 1) < 1e-12 and abs(r["rmse_m"] - 0.3) < 1e-12, f"NEES {r['NEES']} RMSE {r['rmse_m']}")


def bad_inputs(d):
    gt = [(0.0, "a", 0.0, 0.0, ["c1"])]
    g, h = write_case(d, gt, [(0.0, "T", 0.0, 0.0, 0.5, 0.5, 0.0)])

    def expect(args, code, words, what):
        p = subprocess.run([ROADSIDE, "eval", *args], capture_output=True, text=True)
        check(p.returncode == code and all(w in p.stderr for w in words),
              f"{what}: exit {p.returncode} (expected {code}), stderr {p.stderr!r} lacks {words}")

    bad = os.path.join(d, "bad.csv")
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m\n0,T,1\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:1", "n_m"], "missing column")
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m,n_m\n0,T,1,x\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:2", "n_m", "not a number"], "not a number")
    # issue 42: a NUL byte dropped every later row; 0x10 read as 16
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m,n_m\n0,T,1,1\n\0\n1,T,2,2\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:3", "NUL"], "a NUL byte")
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m,n_m\n0,T,0x10,1\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:2", "e_m", "not a number"], "hexadecimal")
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m,n_m\n0,T,1,1\n0,T,2,2\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:3", "track_id"], "a track twice at one time")
    with open(bad, "w") as f:
        f.write("time_s,track_id,e_m,n_m\n0,T,1\n")
    expect(["--tracks", bad, "--gt-tracks", g], 1, ["bad.csv:2", "fields"], "short row")
    expect(["--tracks", h, "--gt-tracks", os.path.join(d, "nope.csv")], 1, ["nope.csv"], "missing file")
    expect(["--tracks", h, "--gt-tracks", g, "--threshold-m", "-1"], 2, ["--threshold-m"], "negative threshold")
    expect(["--tracks", h], 2, ["--gt-tracks"], "no ground truth")
    out = os.path.join(d, "never.json")
    expect(["--tracks", bad, "--gt-tracks", g, "-o", out], 1, ["bad.csv"], "bad input with -o")
    check(not os.path.exists(out), "bad input: an output file was written")


def main():
    nrandom = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    seed = 3901
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory() as d:
        hand_cases(d)
        bad_inputs(d)
        for i in range(nrandom):
            gt, tr = random_case(rng)
            all_gt = i % 4 == 3
            got = run(d, gt, tr, *(["--all-gt"] if all_gt else []))
            compare(got, oracle(gt, tr, 2.0, all_gt), f"random case {i} (seed {seed}, all_gt {all_gt})")
            if len(FAILS) > 10:
                break
    if FAILS:
        print(f"{len(FAILS)} failure(s); seed {seed}")
        sys.exit(1)
    print(f"hand cases, bad input and {nrandom} random cases agree with the oracle (seed {seed})")


if __name__ == "__main__":
    main()
