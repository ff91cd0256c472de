// rs_units.h -- the one pair of angle-unit constants. Multiply degrees by RS_RAD_PER_DEG to get
// radians, radians by RS_DEG_PER_RAD to get degrees: each name says what it converts, so it
// cannot be read backwards (a bare DEG was, in both directions). No file defines its own.
//
// The values are the correctly rounded quotients of the literal pi (M_PI's digits) and 180, the
// same doubles as M_PI / 180.0 and 180.0 / M_PI. Note that x * RS_RAD_PER_DEG and
// x * M_PI / 180 (which is (x * M_PI) / 180) can differ in the last bit.
#pragma once

#define RS_RAD_PER_DEG (3.14159265358979323846 / 180.0)
#define RS_DEG_PER_RAD (180.0 / 3.14159265358979323846)
