// PLACEHOLDER
typedef int rs_placeholder_rs_calib_bench;
