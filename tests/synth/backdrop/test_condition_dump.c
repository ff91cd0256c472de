// test_condition_dump IMAGE.png... -- issue 40: the condition estimated from each image
// (rs_synth_condition_estimate on the image decoded to linear light), one line per image:
// "<label> ground_lum sky_lum ground_sat"; then "fresnel" and Fresnel's reflectance of water
// at cos_i = 1, 0.5, 0.1, 0.02 (rs_synth_fresnel_water). For tests/synth/backdrop/test_condition.py.
// Exit 1 (with the message) on any error.
#include <stdio.h>

#include "core/rs_color.h"
#include "core/rs_image.h"
#include "synth/backdrop/rs_synth_condition.h"

int main(int argc, char **argv)
{
    for (int a = 1; a < argc; a++) {
        rs_err err = {0};
        rs_image img = {0};
        rs_synth_condition c;
        rs_status st = rs_image_read(&img, argv[a], &err);
        if (!st)
            for (size_t i = 0; i < (size_t)img.width * img.height * img.channels; i++)
                img.data[i] = (float)rs_color_srgb_decode(img.data[i]);
        if (!st) st = rs_synth_condition_estimate(&c, &img, &err);
        rs_image_free(&img);
        if (st) {
            fprintf(stderr, "%s: %s\n", argv[a], err.msg);
            return 1;
        }
        char label[16];
        rs_synth_condition_label(label, sizeof(label), &c);
        printf("%s %.6f %.6f %.6f\n", label, c.ground_lum, c.sky_lum, c.ground_sat);
    }
    printf("fresnel %.6f %.6f %.6f %.6f\n", rs_synth_fresnel_water(1), rs_synth_fresnel_water(0.5),
           rs_synth_fresnel_water(0.1), rs_synth_fresnel_water(0.02));
    return 0;
}
