/* Float to text for every text writer (OBJ, .skel, the glTF JSON): the shortest decimal that
 * reads back as the same float, from Dragonbox (stems/src/float_text.cpp, C++). Not installed.
 * See docs/mesh-export.md, "Numbers". */
#ifndef XYL_FLOAT_TEXT_H
#define XYL_FLOAT_TEXT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Longest text xyl__float_text writes: "-0.0000123456789" (16), and room to spare. */
#define XYL__FLOAT_TEXT_MAX 24

/* Writes v into out (no NUL) and returns the length. A finite v gets the fewest significant
 * digits that strtof (round to nearest) reads back as exactly v, sign included ("-0" for -0.0):
 * plain when its first digit is at 10^-5 .. 10^8 ("0.1", "-2.5", "16777216", "0.00001"),
 * else one digit before the point and an exponent ("1e-07" is "1e-7", "3.4028235e38"); '.' and
 * 'e' whatever the locale, valid JSON. NaN and infinities, which the writers refuse before they
 * write, give "nan", "inf" and "-inf". */
size_t xyl__float_text(float v, char out[XYL__FLOAT_TEXT_MAX]);

/* Longest text xyl__double_text writes: "-0.0000" and 17 digits (24), "-1.2345678901234567e-308"
 * (24), and room to spare. */
#define XYL__DOUBLE_TEXT_MAX 32

/* The same for a double: the fewest significant digits that strtod reads back as exactly v,
 * plain when the first digit is at 10^-5 .. 10^16, else with an exponent. The writers use it for
 * world positions (a local origin plus a float offset), which a float would round. */
size_t xyl__double_text(double v, char out[XYL__DOUBLE_TEXT_MAX]);

#ifdef __cplusplus
}
#endif

#endif
