/*
 * thorax/io/dipoles_file.h — current dipole sources for the forward problem (io layer;
 * docs/formats.md, "Dipoles"; used by thx_forward_dipoles in thorax/fem/fem.h).
 *
 * A set of n dipoles at fixed positions (mm) and n_frames frames of their moments (mA·m):
 * frame f is the field of all n dipoles at once, dipole i with moment moment[3 (f n + i) + c].
 * Two layouts of the file are read:
 *  - OpenMEEG's .dip: one dipole a line, `px py pz qx qy qz` (six numbers); each line is a
 *    source of its own, so the file is n dipoles and n frames, frame k holding dipole k's moment
 *    and zero for the others (OpenMEEG's gain matrices have one column per dipole the same way).
 *    `separate` is 1 then.
 *  - thorax's time series: a first line `thorax-dipoles 1`, `dipoles N`, N lines `px py pz`,
 *    `frames F` (optionally `frames F TIME_UNIT`), F lines `t q1x q1y q1z ... qNx qNy qNz`, `end`.
 * In both, `#` starts a comment and blank lines are skipped. Units are not scaled on reading:
 * positions are in the model's millimetres, moments in mA·m (1 mA·m = 10^6 nA·mm), and the
 * potentials thx_forward_dipoles gives are then in mV.
 */
#ifndef THORAX_IO_DIPOLES_FILE_H
#define THORAX_IO_DIPOLES_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t n;            /* dipoles */
    double *pos;         /* 3 n, mm */
    size_t *line;        /* n: the file's line (1-based) of each dipole's position; 0 if not from a file */
    size_t n_frames;
    double *time;        /* n_frames (the .dip layout: the dipole's number, 1..n) */
    double *moment;      /* 3 n n_frames, mA·m, frame-major: moment[3 (f n + i) + c] */
    size_t *frame_line;  /* n_frames: the file's line of each frame's moments; 0 if not from a file */
    int separate;        /* 1: the .dip layout (frame k = dipole k alone) */
    char time_unit[16];  /* "dipole" for the .dip layout; the file's word, else "" */
    char path[512];      /* the file read ("" otherwise): messages name it */
} thx_dipoles;

/* A set of n dipoles and n_frames frames, all zero. Caller destroys. */
thx_status thx_dipoles_create(thx_ctx *ctx, size_t n, size_t n_frames, thx_dipoles **out);
void thx_dipoles_destroy(thx_dipoles **d);

/* Reads either layout (told by the first line). Errors name the file and line: a line that is not
 * six numbers (.dip), a count that disagrees with the lines, a value that is not a finite number
 * (NaN, Inf, text), trailing text, no dipole. Caller destroys *out. */
thx_status thx_dipoles_read(thx_ctx *ctx, const char *path, thx_dipoles **out);

#ifdef __cplusplus
}
#endif
#endif
