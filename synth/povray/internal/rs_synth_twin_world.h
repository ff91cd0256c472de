// rs_synth_twin_world.h -- the digital twin's world, shared by the camera backgrounds
// (rs_synth_twin.c) and the orthophoto (rs_synth_ortho.c): one scene, two cameras.
// Written by rs_synth_twin_world.c; docs/backgrounds.md ("What the twin draws").
#pragma once
#include <stdbool.h>
#include <stdio.h>

#include "core/rs_status.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"

// Dimensions of the twin's markings and kerbs, metres. Distances along a lane are measured
// from the lane's end at the junction (for a lane entering it) or from its start (leaving it).
// The values are stated choices within the ranges of the standards: a crosswalk at least 3 m
// deep (German R-FGUe 2001: 3 to 4 m; MUTCD 2009 3B.18: at least 6 ft) of stripes 0.5 m wide
// with 0.5 m gaps (R-FGUe), a stop line 12 to 24 in (0.3 to 0.6 m) wide at least 4 ft (1.2 m)
// before the crosswalk (MUTCD 3B.16), a 5 m arrow (German RMS: 5 m in towns), a 12 cm kerb.
typedef struct {
    double crosswalk_gap_m;    // 0.5: lane end to the crosswalk
    double crosswalk_depth_m;  // 3.0: along the lane
    double crosswalk_period_m; // 1.0: stripe + gap; a lane of width w gets n = round(w / period)
                               //   stripes of width w/(2n) centred at -w/2 + (k + 1/2) w/n
    double stop_gap_m;         // 1.2: crosswalk to stop bar
    double stop_depth_m;       // 0.40: the stop bar, across the whole lane width
    double arrow_tip_m;        // 8.0: lane end to the arrow's tip
    double arrow_length_m;     // 5.0: tail to tip
    double kerb_height_m;      // 0.12: sidewalks above the road
    double shoulder_m;         // 0.5: road beyond each lane's edge before the kerb
    double road_extend_m;      // 100: the road continues past lanes' open ends
} rs_synth_twin_dims;
extern const rs_synth_twin_dims rs_synth_twin_dims_default;

// A turn of more than this from the lane's last heading to the end of its junction path is a
// left (counter-clockwise) or right turn; less is straight on.
#define RS_SYNTH_TWIN_STRAIGHT_DEG 30.0

// What the twin draws at a lane's ends, from lanes.geojson alone.
typedef struct {
    bool enters_junction;       // not a junction path, and one of its `next` is (kind "junction"):
                                //   crosswalk, stop bar and arrow at its end
    bool leaves_junction;       // not a junction path, and a junction path continues into it: crosswalk
                                //   at its start
    bool has_predecessor;       // some lane continues into it (else the road extends past its start)
    bool straight, left, right; // the arrow's heads: the turns of its `next` junction paths
} rs_synth_twin_role;
rs_synth_twin_role rs_synth_twin_lane_role(const rs_lanes *lanes, int i);

// The arrow's shape, in the frame of its tail (u along the lane towards the junction, v to the
// left, metres, for a 5 m arrow; scaled by arrow_length_m / 5): a stem u in [0, 3.4] (2.1
// without a straight head), |v| <= 0.1; a straight head, the triangle (3.4, -0.45), (5.0, 0),
// (3.4, 0.45); a left branch from (2.0, 0) along 45 degrees to the left, 0.9 long and 0.2 wide,
// then a head 1.1 long and 0.8 wide at its base; a right branch mirrored.

// True for sunny, cloudy, rain, snow, night.
bool rs_synth_twin_weather_ok(const char *weather);

// Writes everything of a twin scene but its camera (and the #version / global_settings header):
// the sky colour, the sun at (sun_az, sun_el) degrees when the weather has one and it is up, the
// sky (7 parallel lights, the scene's own directions, casting shadows when sky_shadows: the
// kerbs' and poles' soft shadows, 40% of the trace time), the site's ground plane
// (asphalt: grain, bump, patches), and with lanes: sidewalks raised by the kerb height outside
// the road (every lane's outline widened by the shoulder, the junction paths' hull) and the
// markings: white lane edges marking_width_m wide on both edges of every lane that is not a
// junction path, and where a lane enters a junction a crosswalk, a stop bar and a turn arrow,
// where one leaves it a crosswalk (rs_synth_twin_dims). lanes may be NULL or empty: none.
// POV-Ray world <x, y, z> = <east, up, north>, metres.
// weather: sunny, cloudy, rain, snow or night (RS_ERR_INVALID otherwise). RS_ERR_IO when the
// stream reports an error.
rs_status rs_synth_twin_world_write(FILE *f, const rs_site *site, const rs_lanes *lanes, const char *weather,
                                    double sun_az, double sun_el, double marking_width_m, bool sky_shadows,
                                    rs_err *err);
