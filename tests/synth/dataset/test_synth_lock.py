#!/usr/bin/python3
# Issue 14, finding 6 (first half): two `roadside synth` runs into one folder. Before the fix both
# failed ("work/000000_cam1/passes1.png: cannot read the image"); now the second fails at once,
# naming the first's pid, and leaves the folder as it was.
#
# Oracles: Python's fcntl.flock on DATASET/.lock as "another holder" (the kernel's lock, not
# roadside's word), the folder's entries (names, sizes, inodes, mtimes) before and after, and a
# real first run (its pid from Popen). A holder killed with SIGKILL leaves no stale lock.
import fcntl
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 14


def synth_args(calib, out, count=2):
    return [u.ROADSIDE, "synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--count", str(count), "-o", out,
            "--seed", str(SEED), "--camera", "cam1", "--size", "64x36", "--vehicles", "3",
            "--jobs", "1"]


def snapshot(d):
    """Every entry under d (d included): relative path -> (size, inode, mtime_ns), links not
    followed."""
    out = {}
    for root, dirs, files in os.walk(d):
        for name in [""] + dirs + files:
            path = os.path.join(root, name) if name else root
            st = os.lstat(path)
            out[os.path.relpath(path, d)] = (st.st_size, st.st_ino, st.st_mtime_ns)
    return out


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=60)


def expect_refused(args, out, pid, what):
    before = snapshot(out)
    p = run(args)
    if p.returncode != 1:
        u.fail("%s: exit %d, expected 1\n%s%s" % (what, p.returncode, p.stdout, p.stderr), SEED)
    msg = p.stderr.strip()
    if "is in use by" not in msg or (pid is not None and "(pid %d)" % pid not in msg):
        u.fail("%s: the message does not name the holder (pid %s): %s" % (what, pid, msg), SEED)
    after = snapshot(out)
    if after != before:
        changed = sorted(set(after.items()) ^ set(before.items()))
        u.fail("%s: the folder changed: %s" % (what, changed), SEED)
    print("%s: refused, folder unchanged: %s" % (what, msg))


def check_dataset(out, count):
    coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
    if len(coco["images"]) != count:
        u.fail("%s: %d images in the COCO file, expected %d" % (out, len(coco["images"]), count))
    if os.path.exists(os.path.join(out, ".lock")):
        u.fail("%s/.lock left behind by a run that ended" % out)


def mark(folder):
    """Marks folder as a dataset folder of roadside's (DATASET/.roadside-dataset, docs/synth.md)."""
    with open(os.path.join(folder, ".roadside-dataset"), "w") as f:
        f.write("roadside synth dataset\n")


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)

        # 1. another holder (Python), having written its line: refused with its pid
        out = os.path.join(tmp, "held")
        os.makedirs(out)
        mark(out)  # a dataset folder (issue 42: synth writes only in folders it marked)
        with open(os.path.join(out, "keep.txt"), "w") as f:
            f.write("a file of the user's\n")
        fd = os.open(os.path.join(out, ".lock"), os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, ("%d 2030-01-02T03:04:05+0000 roadside synth\n" % os.getpid()).encode())
        expect_refused(synth_args(calib, out), out, os.getpid(), "held by python")
        # a holder that has not written its line yet: still refused
        os.ftruncate(fd, 0)
        expect_refused(synth_args(calib, out), out, None, "held, no line yet")
        # 2. the holder ends without removing .lock (a crash): no stale lock, the run goes on
        os.close(fd)
        p = run(synth_args(calib, out))
        if p.returncode != 0:
            u.fail("after the holder ended: exit %d\n%s" % (p.returncode, p.stderr), SEED)
        check_dataset(out, 2)
        print("holder gone, its .lock left: the next run takes it (%s)" % p.stdout.splitlines()[0])
        # `synth merge` locks its OUT the same way
        merged = os.path.join(tmp, "merged")
        os.makedirs(merged)
        mark(merged)
        fd = os.open(os.path.join(merged, ".lock"), os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, ("%d 2030-01-02T03:04:05+0000 roadside synth\n" % os.getpid()).encode())
        expect_refused([u.ROADSIDE, "synth", "merge", out, "-o", merged], merged, os.getpid(),
                       "merge into a held folder")
        os.close(fd)

        # 3. a real first run holds the folder: the second fails with the first's pid
        out = os.path.join(tmp, "race")
        first = subprocess.Popen(synth_args(calib, out, count=6), stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        lock = os.path.join(out, ".lock")
        t0 = time.time()
        while time.time() - t0 < 20:
            if os.path.exists(lock) and open(lock).read().strip():
                break
            time.sleep(0.02)
        else:
            first.kill()
            u.fail("the first run never wrote %s" % lock, SEED)
        if first.poll() is not None:
            u.fail("the first run ended before the second could start (too fast to test)")
        p = run(synth_args(calib, out, count=6))
        if p.returncode != 1 or "(pid %d)" % first.pid not in p.stderr:
            first.kill()
            u.fail("second run: exit %d, expected 1 naming pid %d\n%s"
                   % (p.returncode, first.pid, p.stderr), SEED)
        print("second run while the first (pid %d) runs: %s" % (first.pid, p.stderr.strip()))
        so, se = first.communicate(timeout=120)
        if first.returncode != 0:
            u.fail("the first run failed beside the refused one: %s" % se, SEED)
        check_dataset(out, 6)
        print("first run unharmed: %s" % so.splitlines()[0])

        # 4. a holder killed with SIGKILL (workers and povray die with it): no stale lock
        out = os.path.join(tmp, "killed")
        first = subprocess.Popen(synth_args(calib, out, count=6), stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        t0 = time.time()
        while not os.path.exists(os.path.join(out, ".lock")) and time.time() - t0 < 20:
            time.sleep(0.02)
        time.sleep(0.3)
        first.send_signal(signal.SIGKILL)
        first.wait()
        p = run(synth_args(calib, out, count=6))
        if p.returncode != 0:
            u.fail("after SIGKILL of the holder: exit %d\n%s" % (p.returncode, p.stderr), SEED)
        check_dataset(out, 6)
        print("holder killed: the rerun completes (%s)" % p.stdout.splitlines()[0])

        # 5. a link planted as DATASET/.lock is refused, never followed
        out = os.path.join(tmp, "link")
        os.makedirs(out)
        mark(out)
        target = os.path.join(tmp, "target.txt")
        with open(target, "w") as f:
            f.write("not roadside's\n")
        os.symlink(target, os.path.join(out, ".lock"))
        p = run(synth_args(calib, out))
        if p.returncode != 1 or ".lock" not in p.stderr or open(target).read() != "not roadside's\n":
            u.fail("a link as .lock: exit %d, %s" % (p.returncode, p.stderr), SEED)
        print("a link as .lock: refused (%s)" % p.stderr.strip())
    print("OK")


if __name__ == "__main__":
    main()
