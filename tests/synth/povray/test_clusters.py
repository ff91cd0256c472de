#!/usr/bin/env python3
# The colour pass in clusters (synth/povray/rs_synth_render_cull.c, rs_synth_colour_clusters) and
# its camera cut to each cluster's rectangle (rs_synth_povcam_crop), with the real POV-Ray,
# against one povray process over the whole frame (--full-frame: no culling, no region, no cut):
#   - the default render of 3 vehicles apart across a 960 x 600 image runs 2 to 4 colour processes
#     (the empty pixels between them cost more than a povray process each: CLUSTER_PROCESS_PX);
#   - ids.png is identical, so is the alpha of rgba.png (the ID pass gives both);
#   - image.png differs by more than 8/255 on at most 2 % of the vehicles' pixels (a vehicle of
#     another cluster more than 4 m away is not seen reflected in this one's paint; everything
#     else traces the same rays);
#   - a vehicle alone (one cluster: the cut camera alone): ids.png and alpha identical, image.png
#     within 4/255 on all but 0.2 % of its pixels (POV-Ray's shadow cache traces a region and the
#     whole frame in another order: docs/fleet.md, "Cost").
import os
import re
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 7


def render(common, out, extra):
    p = u.run(common + ["-o", out] + extra)
    m = re.search(r"passes \d+ processes (\d+)", p.stdout)
    if not m:
        u.fail("no 'processes N' in: %s" % p.stdout, SEED)
    return int(m.group(1))


def main():
    u.need_povray()
    import cv2
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp, 960, 600)
        bg_path = os.path.join(tmp, "bg.png")
        cv2.imwrite(bg_path, np.full((H, W, 3), 128, np.uint8))
        # three sedans apart across the image (left, middle far, right), standing where these
        # pixels look at the ground
        import mrcal
        rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
        vs = []
        for k, (fu, fv, yaw) in enumerate(((0.15, 0.85, 30), (0.5, 0.62, 100), (0.85, 0.85, 250))):
            d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(np.array([fu * W, fv * H]), lens, intr))
            c = rt_enu_cam[3:]
            p = c - c[2] / d[2] * d
            vs.append({"class": "sedan", "e": float(p[0]), "n": float(p[1]), "yaw_deg": yaw, "id": "v%d" % k})
        for name, subset in (("many", vs), ("one", vs[:1])):
            veh = os.path.join(tmp, name + ".json")
            u.write_json(veh, subset)
            common = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                      "--background", bg_path, "--shadows", "--sun", "200,35"]
            a, b = os.path.join(tmp, name + "_clusters"), os.path.join(tmp, name + "_whole")
            na = render(common, a, [])
            render(common, b, ["--full-frame"])
            img = {k: [cv2.imread(os.path.join(d, k), -1) for d in (a, b)]
                   for k in ("ids.png", "rgba.png", "image.png")}
            if not np.array_equal(*img["ids.png"]):
                u.fail("%s: ids.png differs from the whole frame's" % name, SEED)
            if not np.array_equal(img["rgba.png"][0][..., 3], img["rgba.png"][1][..., 3]):
                u.fail("%s: the alpha of rgba.png differs from the whole frame's" % name, SEED)
            veh_px = img["ids.png"][0] > 0
            d = np.abs(img["image.png"][0].astype(int) - img["image.png"][1].astype(int)).max(axis=2)
            frac = float((d[veh_px] > 8).mean()) if veh_px.any() else 1.0
            print("%s: %d colour processes; %d vehicle pixels, %.2f %% differ by more than 8/255 (max %d)"
                  % (name, na, int(veh_px.sum()), 100 * frac, int(d.max())))
            if name == "many":
                if not 2 <= na <= 4:
                    u.fail("many: %d colour processes, expected 2 to 4 clusters" % na, SEED)
                if frac > 0.02:
                    u.fail("many: %.2f %% of the vehicle pixels differ (bound 2 %%)" % (100 * frac), SEED)
            elif float((d[veh_px] > 4).mean()) > 0.002:  # POV-Ray's shadow cache: a region and
                # the whole frame trace in another order (docs/fleet.md, "Cost": bound 0.2 %)
                u.fail("one: %.2f %% of the vehicle pixels differ by more than 4/255 (bound 0.2 %%)"
                       % (100 * float((d[veh_px] > 4).mean())), SEED)
    print("all cluster checks passed")


if __name__ == "__main__":
    main()
