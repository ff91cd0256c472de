#!/usr/bin/env python3
# test_site_cli.py -- `roadside site` argument handling: --help everywhere (exit 0, lists every
# subcommand including simulate), `site simulate` reaches the simulator's own command, usage
# errors exit 2, a missing site exits 1 with a message naming the file.
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402


def expect(args, status, needle=None, stream="out"):
    rc, out, err = fx.run(*args)
    text = out if stream == "out" else err
    if rc != status or (needle and needle not in text):
        fx.fail("roadside %s: exit %d (expected %d), looking for %r" % (" ".join(args), rc, status, needle),
                out, err)
    return out, err


def main():
    out, _ = expect(["site", "--help"], 0, "usage: roadside site check SITE")
    for sub in ("check", "describe", "init", "simulate"):
        if "roadside site %s" % sub not in out:
            fx.fail("site --help does not list %s" % sub, out)
    for sub in ("check", "describe", "init"):
        expect(["site", sub, "--help"], 0, "usage: roadside site")
    expect(["help", "site"], 0, "usage: roadside site")
    # simulate is dispatched to its own command: never our usage or an unknown-subcommand error
    rc, out, err = fx.run("site", "simulate", "--help")
    if "unknown subcommand" in out + err or "usage: roadside site check" in out + err:
        fx.fail("site simulate is not dispatched to rs_cli_site_simulate", out, err)
    expect(["site"], 2)
    expect(["site", "frobnicate"], 2, "unknown subcommand 'frobnicate'", "err")
    expect(["site", "check"], 2, "check takes one SITE folder", "err")
    expect(["site", "describe"], 2, "missing SITE", "err")
    expect(["site", "describe", "--bogus", "x"], 2, "unknown option", "err")
    expect(["site", "init", "x"], 2, "missing --origin", "err")
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        expect(["site", "check", "NOPE"], 1, "NOPE/site.json: missing file")
        expect(["site", "describe", "NOPE"], 1, "NOPE/site.json: missing file", "err")
        os.chdir("/")
    print("site cli: help, dispatch, usage errors ok")


if __name__ == "__main__":
    main()
