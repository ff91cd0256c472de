#!/usr/bin/python3
# Issue 14, finding 8: what confines povray. `render --help` said povray's file I/O was
# restricted to OUTDIR; POV-Ray 3.7.0.10 enforces none of the povray.conf roadside writes. Now
# povray runs under Linux Landlock (synth/povray/rs_synth_sandbox.h, docs/povray.md "Confinement").
#
# Checked, with povray run exactly as roadside runs it (rs_synth_povray_run, through
# test_povray_sandbox_run) in an OUTDIR that `roadside render --keep` made (its povray.conf):
#   confined (Landlock available): scenes that #fopen/#read /etc/passwd, #include it, read a file
#     beside OUTDIR, #write to /tmp, /var/tmp and OUTDIR/.. are refused ("Cannot open", no file
#     made); writing inside OUTDIR and a real render still work;
#   ROADSIDE_POVRAY_SANDBOX=off, or no Landlock: the cli notes that povray runs unconfined; what
#     povray's own restriction lets through is printed (the measurement docs/povray.md quotes);
#   always (the first line of defence): no string field of a vehicles file (id, class, colour,
#     model) puts a directive into a scene: ids only as sanitised comments, the rest refused.
# Oracles: the file system (does the file exist afterwards?) and povray's own log.
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 8
EVIL = 'x"\n#fopen F "/tmp/rs_owned" write #write (F, "x") #fclose F\n//'


def probe(helper, env=None):
    return subprocess.run([helper, "probe"], capture_output=True, text=True,
                          env=env).stdout.strip()


def run_scene(helper, outdir, name, body, env=None):
    """Writes OUTDIR/name.pov and runs it as roadside runs povray: (succeeded, log text)."""
    with open(os.path.join(outdir, name + ".pov"), "w") as f:
        f.write("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n" + body + "\n")
    log = os.path.join(outdir, "povray.log")
    if os.path.exists(log):
        os.remove(log)
    p = subprocess.run([helper, "run", outdir, name + ".pov"], capture_output=True, text=True,
                       env=env, timeout=60)
    return p.returncode == 0, open(log).read() if os.path.exists(log) else ""


def hostile_scenes(tmp, outdir):
    """(name, SDL, file that must not appear or None, what it tries)."""
    uniq = os.path.basename(tmp)
    out = [("read_passwd", '#fopen F "/etc/passwd" read\n#read (F, S)\n#fclose F', None,
            "read /etc/passwd"),
           ("include_passwd", '#include "/etc/passwd"', None, "#include /etc/passwd"),
           ("read_beside", '#fopen F "../secret.txt" read\n#fclose F', None,
            "read OUTDIR/../secret.txt"),
           ("write_tmp", '#fopen F "/tmp/%s_owned" write\n#write (F, "x")\n#fclose F' % uniq,
            "/tmp/%s_owned" % uniq, "write /tmp"),
           ("write_parent", '#fopen F "../owned" write\n#write (F, "x")\n#fclose F',
            os.path.join(tmp, "owned"), "write OUTDIR/.."),
           ("write_abs_parent", '#fopen F "%s" write\n#write (F, "x")\n#fclose F'
            % os.path.join(tmp, "owned_abs"), os.path.join(tmp, "owned_abs"),
            "write beside OUTDIR by absolute path")]
    if os.path.isdir("/var/tmp"):
        out.append(("write_vartmp", '#fopen F "/var/tmp/%s_owned" write\n#write (F, "x")\n'
                    '#fclose F' % uniq, "/var/tmp/%s_owned" % uniq, "write /var/tmp"))
    return out


def check_sanitiser(tmp, calib, model):
    """The first line of defence, whatever confines povray: no string field of the vehicles
    file reaches a scene as anything but a sanitised comment."""
    vs = u.ground_vehicles(model, 2, SEED)
    for v in vs:
        v["id"] = EVIL
    veh = os.path.join(tmp, "evil_ids.json")
    u.write_json(veh, vs)
    out = os.path.join(tmp, "evil_out")
    u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o", out,
           "--keep", "--full-frame"])
    for name in os.listdir(out):
        if not name.endswith(".pov"):
            continue
        text = open(os.path.join(out, name)).read()
        directives = set(re.findall(r"#\s*([a-z_]+)", text))
        if not directives <= {"version", "declare", "switch", "case", "break", "end"}:
            u.fail("%s: directives %s from a hostile id" % (name, sorted(directives)), SEED)
        if "rs_owned" in text and not re.search(r"//[^\n]*rs_owned", text):
            u.fail("%s: the hostile id reached the scene outside a comment" % name, SEED)
    if os.path.exists("/tmp/rs_owned"):
        u.fail("/tmp/rs_owned exists after rendering hostile ids", SEED)
    # the other string fields are refused before any scene is written
    for field, value in (("class", 'sedan"\n#include "/etc/passwd"'),
                         ("colour", '#fff"\n#include "/etc/passwd"'),
                         ("model", 'x"\n#include "/etc/passwd".obj')):
        v = dict(vs[0])
        v.pop("class")
        v[field] = value
        if field == "colour":
            v["class"] = "sedan"
        path = os.path.join(tmp, "evil_%s.json" % field)
        u.write_json(path, [v])
        o = os.path.join(tmp, "evil_%s" % field)
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", path,
                   "-o", o, "--keep"], expect=None)
        if p.returncode == 0:
            u.fail("a hostile \"%s\" was accepted" % field, SEED)
        scenes = [n for n in os.listdir(o) if n.endswith(".pov")] if os.path.isdir(o) else []
        if scenes:
            u.fail("a hostile \"%s\" left a scene: %s" % (field, scenes), SEED)
        print("hostile \"%s\": refused: %s" % (field, p.stderr.strip().splitlines()[-1][:120]))
    print("sanitiser: ids only in comments; class, colour, model refused")


def main():
    u.need_povray()
    helper = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp, 64, 40)
        vs = u.ground_vehicles(model, 2, SEED)
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        outdir = os.path.join(tmp, "out")
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                   "-o", outdir, "--keep", "--full-frame"])
        with open(os.path.join(tmp, "secret.txt"), "w") as f:
            f.write("beside OUTDIR\n")
        box = probe(helper)
        print("probe: %s" % box)
        confined = box.startswith("landlock ABI")
        if confined == ("unconfined" in p.stderr):
            u.fail("render's note disagrees with the probe (%s): %s" % (box, p.stderr), SEED)

        off = dict(os.environ, ROADSIDE_POVRAY_SANDBOX="off")
        if not probe(helper, off).startswith("unconfined: ROADSIDE_POVRAY_SANDBOX=off"):
            u.fail("ROADSIDE_POVRAY_SANDBOX=off not honoured: " + probe(helper, off))
        p_off = subprocess.run([u.ROADSIDE, "render", u.DEMO, "--calib", calib, "--camera", "cam1",
                                "--vehicles", veh, "-o", os.path.join(tmp, "out_off")],
                               capture_output=True, text=True, env=off)
        if p_off.returncode != 0 or \
                "note: povray runs unconfined: ROADSIDE_POVRAY_SANDBOX=off" not in p_off.stderr:
            u.fail("no note when povray runs unconfined: exit %d, %s" % (p_off.returncode,
                                                                       p_off.stderr))
        print("ROADSIDE_POVRAY_SANDBOX=off: %s" % p_off.stderr.strip())

        scenes = hostile_scenes(tmp, outdir)
        if confined:
            for name, sdl, made, what in scenes:
                ok, log = run_scene(helper, outdir, name, sdl)
                if ok or "Cannot open" not in log:
                    u.fail("confined povray did not refuse to %s:\n%s" % (what, log[-600:]), SEED)
                if made and os.path.exists(made):
                    u.fail("confined povray made %s" % made, SEED)
                print("confined: %-40s refused (%s)" % (what, [x for x in log.splitlines()
                                                              if "Cannot open" in x][-1].strip()))
            ok, log = run_scene(helper, outdir, "write_inside",
                                '#fopen F "inside.txt" write\n#write (F, "x")\n#fclose F')
            if not ok or not os.path.exists(os.path.join(outdir, "inside.txt")):
                u.fail("confined povray cannot write inside OUTDIR:\n" + log[-600:], SEED)
            print("confined: writing inside OUTDIR and rendering work")
        else:
            print("Landlock is not available here (%s): the confinement is not testable; "
                  "the fallback's note and the sanitiser are" % box)

        # What POV-Ray's own restriction (the povray.conf of OUTDIR) lets through: printed, not
        # asserted (docs/povray.md quotes this measurement)
        for name, sdl, made, what in scenes:
            ok, log = run_scene(helper, outdir, name, sdl, env=off)
            passed = (made and os.path.exists(made)) or (not made and "Cannot open" not in log)
            print("unconfined (povray.conf only): %-40s %s" % (what, "PASSES" if passed else
                                                               "refused"))
            if made and os.path.exists(made):
                os.remove(made)

        check_sanitiser(tmp, calib, model)
    print("OK")


if __name__ == "__main__":
    main()
