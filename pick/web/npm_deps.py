#!/usr/bin/env python3
"""Fetches the page's front-end libraries from npm at build time (`npm ci` on pick/web's
package.json and package-lock.json, in the build folder, with its own npm cache there so that a
rebuild needs no network) and copies the files the page serves, for embed.py to compile in.
Usage: npm_deps.py NPM OUTDIR package.json package-lock.json"""
import os
import shutil
import subprocess
import sys

FILES = ["leaflet/dist/leaflet.js", "leaflet/dist/leaflet.css"]


def main():
    npm, outdir, manifest, lock = sys.argv[1:5]
    work = os.path.abspath(os.path.join(outdir, "npm"))
    os.makedirs(work, exist_ok=True)
    for f in (manifest, lock):
        shutil.copyfile(f, os.path.join(work, os.path.basename(f)))
    cmd = [npm, "ci", "--ignore-scripts", "--no-audit", "--no-fund", "--prefer-offline",
           "--cache", os.path.join(work, "cache")]
    r = subprocess.run(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit(f"{lock}: `{' '.join(cmd)}` failed (exit {r.returncode}):\n{r.stdout}")
    for f in FILES:
        shutil.copyfile(os.path.join(work, "node_modules", f), os.path.join(outdir, os.path.basename(f)))


if __name__ == "__main__":
    main()
