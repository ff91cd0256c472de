// test_sun_dump -- reads "lat_deg lon_deg unix_time_s" lines on stdin and prints
// "azimuth_deg elevation_deg" per line with rs_synth_sun_position, for tests/synth/backdrop/test_sun.py;
// also checks the argument validation of rs_synth_sun_position_checked (exit 1 on failure).
#include <math.h>
#include <stdio.h>

#include "synth/backdrop/rs_synth_sun.h"

int main(void)
{
    rs_err err;
    double az, el;
    if (rs_synth_sun_position_checked(&az, &el, 91.0, 0.0, 0.0, &err) != RS_ERR_INVALID ||
        rs_synth_sun_position_checked(&az, &el, 0.0, NAN, 0.0, &err) != RS_ERR_INVALID ||
        rs_synth_sun_position_checked(&az, &el, 0.0, 0.0, INFINITY, &err) != RS_ERR_INVALID ||
        rs_synth_sun_position_checked(NULL, NULL, 10.0, 20.0, 1e9, &err) != RS_OK) {
        fprintf(stderr, "test_sun_dump: argument checks failed\n");
        return 1;
    }
    rs_synth_sun_position(&az, &el, NAN, 0.0, 0.0);
    if (!isnan(az) || !isnan(el)) {
        fprintf(stderr, "test_sun_dump: NaN latitude did not give NaN\n");
        return 1;
    }
    double lat, lon, t;
    while (scanf("%lf %lf %lf", &lat, &lon, &t) == 3) {
        rs_synth_sun_position(&az, &el, lat, lon, t);
        printf("%.9f %.9f\n", az, el);
    }
    return 0;
}
