"""`roadside geo` on bad input: a bad line exits 1 naming the line number and the field (after
streaming the good lines before it), a bad option exits 2; comments, blank lines and comma
separators are handled as --help says."""
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geo_oracle as g  # noqa: E402

ORIGIN = "--origin=45,15,100"

BAD_LINES = [  # args, stdin, lines printed before the error, text the message must contain
    (["enu", ORIGIN], "45 15 0\n# comment\n\n45 x 0\n", 1, ["<stdin>:4:", "field 'lon'", "'x'"]),
    (["enu", ORIGIN], "91 15 0\n", 0, ["<stdin>:1:", "field 'lat'", "outside [-90, 90]"]),
    (["enu", ORIGIN], "45 15 0\n-90.5 0 0\n", 1, ["<stdin>:2:", "field 'lat'"]),
    (["enu", ORIGIN], "45 15\n", 0, ["<stdin>:1:", "expected 3 fields", "found 2"]),
    (["enu", ORIGIN], "45 15 0 7\n", 0, ["<stdin>:1:", "found 4"]),
    (["enu", ORIGIN], "45 15 nan\n", 0, ["<stdin>:1:", "field 'h'", "not a finite number"]),
    (["llh", ORIGIN], "1 2 3\n1 2 3\ninf 0 0\n", 2, ["<stdin>:3:", "field 'e'"]),
    (["llh", ORIGIN], "1 2 1e999\n", 0, ["<stdin>:1:", "field 'u'"]),
    (["enu", ORIGIN, "--from", "utm:33N"], "500000 1e8 0\n", 0, ["<stdin>:1:", "Northing"]),
    (["enu", ORIGIN, "--from", "utm:33N"], "500000 x 0\n", 0, ["<stdin>:1:", "field 'northing'"]),
    (["utm"], "45 15 0\n95 15 0\n", 1, ["<stdin>:2:", "field 'lat'"]),
    (["utm", "--zone", "33n"], "45 -60 0\n", 0, ["<stdin>:1:", "out of legal range"]),
]

BAD_USAGE = [
    ["enu", "--origin", "91,0,0"],
    ["enu", "--origin", "1,2"],
    ["enu", "--origin", "a,b,c"],
    ["enu", "--origin", "nan,0,0"],
    ["enu", "--origin", "1,2,3,4"],
    ["enu", "--origin"],
    ["enu"],
    ["llh", "--origin=45,15,inf"],
    ["enu", ORIGIN, "--from", "utm:61N"],
    ["enu", ORIGIN, "--from", "utm:0N"],
    ["enu", ORIGIN, "--from", "33N"],
    ["llh", ORIGIN, "--from", "utm:33N"],
    ["utm", "--zone", "x"],
    ["utm", ORIGIN],
    ["xyz"],
    [],
]


def run(args, text=""):
    return subprocess.run([g.roadside_exe(), "geo"] + args, input=text, capture_output=True, text=True)


def main():
    for args, text, nprinted, needles in BAD_LINES:
        p = run(args, text)
        what = f"geo {' '.join(args)} <<< {text!r}"
        if p.returncode != 1:
            g.fail(f"{what}: exit {p.returncode}, expected 1; stderr {p.stderr!r}")
        if not p.stderr.startswith("roadside geo: <stdin>:") or any(n not in p.stderr for n in needles):
            g.fail(f"{what}: message {p.stderr!r} lacks {needles}")
        if len(p.stdout.splitlines()) != nprinted:
            g.fail(f"{what}: printed {len(p.stdout.splitlines())} lines before the error, expected {nprinted}")
    for args in BAD_USAGE:
        p = run(args, "45 15 0\n")
        if p.returncode != 2 or p.stdout or "roadside geo" not in p.stderr:
            g.fail(f"geo {' '.join(args)}: exit {p.returncode} (expected 2), stdout {p.stdout!r}, stderr {p.stderr!r}")

    p = run(["--help"])
    if p.returncode != 0 or not all(w in p.stdout for w in ("geo enu", "geo llh", "geo utm", "streamed", "#")):
        g.fail(f"geo --help: exit {p.returncode}, {p.stdout!r}")

    # separators, comments and blank lines
    a = run(["enu", ORIGIN], "45.01 15.02 110\n").stdout
    b = run(["enu", ORIGIN], "# header\n\n  45.01,15.02, 110\r\n\t# more\n").stdout
    if not a or a != b:
        g.fail(f"comma/comment handling: {a!r} != {b!r}")
    print(f"{len(BAD_LINES)} bad lines, {len(BAD_USAGE)} bad usages: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
