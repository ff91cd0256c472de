// rs_cli_detect.h -- what `roadside detect` and `roadside bench detect` share (implemented in
// cmd_detect.c): the commands and the parsing of their common options.
#pragma once
#include "eval/detect/rs_detect.h"

// `roadside detect` (cmd_detect.c)
int rs_cli_detect(int argc, char **argv);
// `roadside bench detect` (cmd_bench_detect.c)
int rs_cli_bench_detect(int argc, char **argv);

// "640" or "640x384" -> *w, *h: whole numbers in [32, 8192], multiples of 32. Returns 0 when
// malformed.
int rs_cli_detect_parse_size(const char *s, int *w, int *h);

// "yolox", "ultralytics" or "auto" -> *f. Returns 0 for anything else.
int rs_cli_detect_parse_family(const char *s, rs_detect_family *f);
