// PLACEHOLDER
typedef int rs_placeholder_calib;
