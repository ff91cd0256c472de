// rs_synth_vehicle.c -- a vehicle on the site's ground plane: its box's corners, the plane's
// height; input text made safe for a scene (synth/fleet/rs_synth_vehicle.h).
#include "synth/fleet/rs_synth_vehicle.h"

#include <ctype.h>

#include "synth/fleet/rs_synth_fleet.h"

// ---- strings ----

// Copies at most n-1 characters of s into out, keeping [A-Za-z0-9 _.:-] and replacing anything
// else by '_': the only form in which an input string ever reaches a scene (inside a comment).
void rs_synth_safe_text(char *out, size_t n, const char *s)
{
    size_t k = 0;
    for (; s && *s && k + 1 < n; s++) {
        const unsigned char c = (unsigned char)*s;
        out[k++] = (isalnum(c) || c == ' ' || c == '_' || c == '.' || c == ':' || c == '-') ? (char)c : '_';
    }
    out[k] = 0;
}

rs_synth_vehicle rs_synth_vehicle_init(rs_synth_class cls)
{
    return (rs_synth_vehicle){.cls = cls, .rgb = {-1, -1, -1}, .lane = -1, .model_cls = RS_SYNTH_USER_MODEL};
}

rs_synth_class rs_synth_vehicle_label_class(const rs_synth_vehicle *v)
{
    return v->cls == RS_SYNTH_USER_MODEL ? v->model_cls : v->cls;
}

// ---- the vehicle box and the ground ----

double rs_synth_ground_up_m(const double ground_normal_enu[3], double ground_offset_m, double e_m, double n_m)
{
    return (ground_offset_m - ground_normal_enu[0] * e_m - ground_normal_enu[1] * n_m) / ground_normal_enu[2];
}

void rs_synth_vehicle_corners_enu(double corners_enu_m[8][3], const rs_synth_vehicle *v,
                                  const double ground_normal_enu[3], double ground_offset_m)
{
    const double up = rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m);
    for (int k = 0; k < 8; k++) {
        const double p_v[3] = {(k & 1 ? 0.5 : -0.5) * v->length_m, (k & 2 ? 0.5 : -0.5) * v->width_m,
                               (k & 4) ? v->height_m : 0};
        rs_synth_vehicle_to_enu(corners_enu_m[k], v, up, p_v);
    }
}
