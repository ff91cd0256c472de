#!/usr/bin/env python3
"""The roadside dispatcher: --help, --version, every subcommand's --help, unknown commands.

Oracle: the version comes from meson's project() (passed as argv[1]); the command list is the
one README.md promises (argv[2:])."""
import os
import subprocess
import sys

roadside = os.environ["ROADSIDE"]
version = sys.argv[1]
commands = sys.argv[2:]
failures = []


def run(*args):
    p = subprocess.run([roadside, *args], capture_output=True, text=True, timeout=60)
    return p.returncode, p.stdout, p.stderr


def check(cond, what):
    if not cond:
        failures.append(what)


rc, out, err = run("--version")
check(rc == 0 and out.strip() == f"roadside {version}", f"--version printed {out!r} rc={rc}")

rc, out, err = run("--help")
check(rc == 0, f"--help exit {rc}")
for c in commands:
    check(f"  {c} " in out, f"--help does not list '{c}'")

for c in commands:
    rc, out, err = run(c, "--help")
    check(rc == 0, f"'{c} --help' exit {rc}: {err.strip()}")
    check(out.startswith(f"usage: roadside {c}"), f"'{c} --help' does not start with its usage line: {out[:80]!r}")
    check("under construction" not in out + err, f"'{c}' is still a placeholder")

rc, out, err = run("no-such-command")
check(rc == 2 and "no-such-command" in err, f"unknown command: rc={rc} err={err!r}")

rc, out, err = run()
check(rc == 2 and "usage" in err, f"no command: rc={rc}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"cli: {len(commands)} commands checked")
