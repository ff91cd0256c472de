// rs_synth_scene_condition.c -- what a background's condition does to a scene: lights on,
// headlights, street lights, snow and slush (rs_synth_scene.h, docs/conditions.md).
#include <math.h>
#include <string.h>

#include "core/rs_units.h"
#include "synth/povray/rs_synth_scene.h"

void rs_synth_scene_headlights(double p_enu_m[2][3], double axis_enu[3], const rs_synth_vehicle *v, double up_m)
{
    const bool two_wheeler = v->cls == RS_SYNTH_MOTORCYCLE || v->cls == RS_SYNTH_BICYCLE;
    const double z = fmin(0.4 * v->height_m, 0.75), y = two_wheeler ? 0 : fmax(0, v->width_m / 2 - 0.25);
    for (int k = 0; k < 2; k++) {
        const double p_v[3] = {v->length_m / 2 + 0.02, k ? -y : y, z};
        rs_synth_vehicle_to_enu(p_enu_m[k], v, up_m, p_v);
    }
    const double yaw = v->yaw_deg * RS_RAD_PER_DEG;
    const double a[3] = {RS_SYNTH_BEAM_AIM_M * sin(yaw), RS_SYNTH_BEAM_AIM_M * cos(yaw), -z};
    const double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int c = 0; c < 3; c++) axis_enu[c] = a[c] / n;
}

double rs_synth_scene_beam(double angle_deg)
{
    if (angle_deg <= RS_SYNTH_BEAM_FULL_DEG) return 1;
    if (angle_deg >= RS_SYNTH_BEAM_EDGE_DEG) return 0;
    const double t = (angle_deg - RS_SYNTH_BEAM_FULL_DEG) / (RS_SYNTH_BEAM_EDGE_DEG - RS_SYNTH_BEAM_FULL_DEG);
    return 0.5 * (1 + cos(M_PI * t));
}

// Street lights at night (rs_synth_scene_apply_condition): the poles nearest the vehicles, else
// lamps beside the first vehicles.
static void street_lights(rs_synth_scene_options *s, const rs_site *site, const rs_synth_prepared *vehicles)
{
    double ce = 0, cn = 0;
    const int N = vehicles ? vehicles->N : 0;
    for (int i = 0; i < N; i++) ce += vehicles->v[i].e_m / N, cn += vehicles->v[i].n_m / N;
    s->Nstreet_lights = 0;
    // selection of the nearest poles, by repeated minimum (at most 8 of a site's few poles)
    bool taken[256] = {false};
    const int Nl = site && site->Nlandmarks < 256 ? site->Nlandmarks : 0;
    while (s->Nstreet_lights < RS_SYNTH_STREET_LIGHTS_MAX) {
        int best = -1;
        double best_d2 = INFINITY;
        for (int j = 0; j < Nl; j++) {
            const rs_site_landmark *l = &site->landmarks[j];
            if (taken[j] || l->shape != RS_SITE_POLE || l->pole_height_m < 4) continue;
            const double de = l->p_enu_m[0] - ce, dn = l->p_enu_m[1] - cn, d2 = de * de + dn * dn;
            if (d2 < best_d2) best_d2 = d2, best = j;
        }
        if (best < 0) break;
        taken[best] = true;
        const rs_site_landmark *l = &site->landmarks[best];
        double *p = s->street_lights_enu_m[s->Nstreet_lights++];
        p[0] = l->p_enu_m[0], p[1] = l->p_enu_m[1], p[2] = l->p_enu_m[2] + l->pole_height_m;
    }
    for (int i = 0; s->Nstreet_lights == 0 && i < N && i < 4; i++) {
        const rs_synth_vehicle *v = &vehicles->v[i];
        const double p_v[3] = {0, -(v->width_m / 2 + 4), 8};
        double up = site ? rs_synth_ground_up_m(site->ground_normal_enu, site->ground_offset_m, v->e_m, v->n_m) : 0;
        rs_synth_vehicle_to_enu(s->street_lights_enu_m[i], v, up, p_v);
        if (i == (N < 4 ? N : 4) - 1) s->Nstreet_lights = i + 1;
    }
    const double led[3] = {1.0, 0.95, 0.85};
    memcpy(s->street_light_rgb, led, sizeof(led));
}

void rs_synth_scene_apply_condition(rs_synth_scene_options *s, const rs_synth_condition *cond, const rs_site *site,
                                    const rs_synth_prepared *vehicles)
{
    const bool night = cond->time_of_day == RS_SYNTH_TOD_NIGHT, dusk = cond->time_of_day == RS_SYNTH_TOD_DUSK;
    s->overcast = s->overcast || cond->overcast;
    s->lights_on = night || dusk;
    if (s->lights_on && !(s->headlight_intensity > 0)) s->headlight_intensity = RS_SYNTH_HEADLIGHT_INTENSITY;
    if (cond->surface == RS_SYNTH_SURFACE_SNOW) s->snow = 0.8, s->dirt_add = 0.35;
    if (cond->surface == RS_SYNTH_SURFACE_WET) s->dirt_add = 0.15;
    if (night) street_lights(s, site, vehicles);
    const double *ls = s->light_rgb_scale;
    if ((night || dusk) && !(ls[0] > 0 || ls[1] > 0 || ls[2] > 0)) {
        const double k[3] = {night ? 0.03 : 0.15, night ? 0.03 : 0.15 * 0.85, night ? 0.035 : 0.15 * 0.7};
        memcpy(s->light_rgb_scale, k, sizeof(k));
        if (!s->env_given) {
            rs_synth_env_default(s->env_zenith_rgb, s->env_horizon_rgb, s->env_ground_rgb, true);
            for (int c = 0; c < 3; c++)
                s->env_zenith_rgb[c] *= k[c], s->env_horizon_rgb[c] *= k[c], s->env_ground_rgb[c] *= k[c];
            s->env_given = true;
        }
    }
}
