// rs_synth_twin.h -- the digital twin's world, shared by the camera backgrounds
// (rs_synth_background.c) and the orthophoto (rs_synth_ortho.c): one scene, two cameras.
#pragma once
#include <stdio.h>

#include "core/rs_status.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"

// Writes everything of a twin scene but its camera (and the #version / global_settings header):
// the sky colour, the sun at (sun_az, sun_el) degrees when the weather has one and it is up, the
// sky light, the site's ground plane (asphalt) and white lane-edge markings marking_width_m wide
// on both edges of every lane that is not a junction path (lanes may be NULL or empty: none).
// POV-Ray world <x, y, z> = <east, up, north>, metres.
// weather: sunny, cloudy, rain, snow or night (RS_ERR_INVALID otherwise). RS_ERR_IO when the
// stream reports an error.
rs_status rs_synth_twin_world_write(FILE *f, const rs_site *site, const rs_lanes *lanes, const char *weather,
                                    double sun_az, double sun_el, double marking_width_m, rs_err *err);
