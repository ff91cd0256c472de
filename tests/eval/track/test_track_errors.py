"""Bad input to `roadside track`: every refusal exits 1 (2 for usage), names the file, the line and
the field at fault, and leaves an existing output untouched (outputs are written atomically).

Cases: a row without time_s (in the second of two files), a wrong header, a field that is not a
number, a wrong number of fields (too few, too many), a covariance that is not positive definite, a missing file, an
empty file; usage: no -o, no input, --gate out of (0, 1), --min-hits 3/2, an unknown option.
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from track_common import HEADER, make_site, run_track, write_located  # noqa: E402
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
from rs_check import check, finish, run  # noqa: E402

GOOD = "1,camA,0,0.0,1,0.9,,,1.0,2.0,0,,,0.3,0.3,0.0\n"


def main():
    with tempfile.TemporaryDirectory() as tmp:
        site = make_site(tmp)
        good = os.path.join(tmp, "good.csv")
        write_located(good, [dict(camera="camA", time_s=0.1 * k, e_m=k, n_m=0, cov=[[0.1, 0], [0, 0.1]])
                             for k in range(5)])
        out = os.path.join(tmp, "tracks.csv")
        with open(out, "w") as f:
            f.write("sentinel\n")

        def bad(name, text, want, code=1, files=None):
            path = os.path.join(tmp, name + ".csv")
            if files is None:
                with open(path, "w") as f:
                    f.write(text)
            p = run_track(site, files or [path], out)
            msg = p.stderr.strip()
            check(p.returncode == code, f"{name}: exit {p.returncode}, want {code} ({msg})")
            for w in want:
                check(w.replace("FILE", path) in msg, f"{name}: message '{msg}' lacks '{w}'")
            with open(out) as f:
                check(f.read() == "sentinel\n", f"{name}: the existing output was touched")
            print(f"{name}: {msg}")
            return path

        no_time = bad("no_time", HEADER + "\n" + GOOD + GOOD.replace(",0.0,1,", ",,1,"), [])
        p = run_track(site, [good, no_time], out)
        check(p.returncode == 1 and f"{no_time}:3: time_s" in p.stderr, f"no time_s, second file: {p.stderr}")
        print("no time_s (second file):", p.stderr.strip())
        bad("header", HEADER.replace("e_m", "x_m") + "\n" + GOOD, ["FILE:1: header"])
        bad("number", HEADER + "\n" + GOOD + GOOD.replace(",1.0,2.0,", ",1.0,north,"), ["FILE:3: n_m", "north"])
        bad("fields", HEADER + "\n" + GOOD.replace(",0.0\n", "\n"), ["FILE:2: cov_en_m2: missing", "15 fields"])
        bad("more_fields", HEADER + "\n" + GOOD.replace(",0.0\n", ",0.0,7\n"), ["FILE:2: 17 fields"])
        bad("covariance", HEADER + "\n" + GOOD.replace(",0.3,0.3,0.0", ",0.3,0.3,0.09"),
            ["FILE:2: sigma_e_m, sigma_n_m, cov_en_m2", "positive definite"])
        bad("negative_sigma", HEADER + "\n" + GOOD.replace(",0.3,0.3,0.0", ",-0.3,0.3,0.0"), ["FILE:2: sigma_e_m"])
        bad("empty", "", ["FILE:1: header", "empty file"])
        missing = os.path.join(tmp, "missing.csv")
        bad("missing", None, [missing], files=[good, missing])
        for args, what in [([site, good], "no -o"), ([site, "-o", out], "no input"),
                           ([site, good, "-o", out, "--gate", "1.5"], "--gate 1.5"),
                           ([site, good, "-o", out, "--min-hits", "3/2"], "--min-hits 3/2"),
                           ([site, good, "-o", out, "--bogus"], "unknown option")]:
            p = run("track", *args)
            check(p.returncode == 2 and "roadside track" in p.stderr, f"{what}: exit {p.returncode}: {p.stderr}")
        p = run_track(site, [good], out)
        check(p.returncode == 0 and open(out).readline().startswith("time_s,track_id,"), f"good input: {p.stderr}")


main()
finish("test_track_errors")
