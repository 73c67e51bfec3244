/*
 * thorax/io/landmarks_file.h — map3d landmark files (.lmarks, .lmark; docs/formats.md,
 * "Landmarks (.lmarks)"; io layer). The set itself is thorax/model/landmarks.h.
 *
 *     11 segment                         number of segments ("segment(s)" may follow)
 *     1 coronary 15                      NUMBER TYPE NPOINTS [INDEX] [R G B]
 *       1.732  5.707 297.844 2.69        X Y Z RADIUS [LABEL], NPOINTS lines
 *       ...
 *     10 stimulus 1
 *     -45.215 35.896 269.921 1.00
 *
 * Millimetres, the frame of the surfaces the landmarks go with.
 */
#ifndef THORAX_IO_LANDMARKS_FILE_H
#define THORAX_IO_LANDMARKS_FILE_H

#include "thorax/model/landmarks.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a landmark file strictly: the segment count on the first line equals the segments that
 * follow, every segment's point count equals its point lines, segments are numbered 1, 2, ... in
 * order, every number is a whole decimal token (finite; no hex, inf, nan), type names are known
 * (thx_landmark_type_names), nothing follows the last segment, and the set passes
 * thx_landmarks_validate. `#` starts a comment; blank lines and CRLF are allowed. Errors name
 * the file, the line and the segment and point ("a.lmarks:9: segment 2 point 3: y 'abc' is not
 * a number"); nothing is returned on failure. Memory grows with the lines read, never with what a
 * count claims. Caller destroys *out; (*out)->path is set to path. */
thx_status thx_landmarks_read(thx_ctx *ctx, const char *path, thx_landmarks **out);
/* The same from memory: text[0..len) (NUL bytes are refused), `name` standing for the file in
 * messages and in (*out)->path. */
thx_status thx_landmarks_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_landmarks **out);

/* Writes the set (validated first; nothing is created if it fails) atomically: the count line,
 * then per segment `NUMBER TYPE NPOINTS [INDEX] [R G B]` and its points. Numbers are written
 * "%.6f" when that reads back to the same double, else "%.17g", so read(write(set)) == set
 * exactly; -0 is written 0. Type names as thx_landmark_type_name gives them (map3d reads them).
 * Byte-identical output for the same set. */
thx_status thx_landmarks_write(thx_ctx *ctx, const thx_landmarks *lm, const char *path);

#ifdef __cplusplus
}
#endif
#endif
