/* Time series (thorax/model/series.h): create, destroy, fiducials and kept fields, non-finite values. */
#include <strings.h>
#include "thorax/model/series.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out)
{
    *out = NULL;
    if (n_frames && n_rows > SIZE_MAX / sizeof(double) / n_frames)
        return thx_error(ctx, THX_EINPUT, "a series of %zu rows x %zu frames is too large", n_rows, n_frames);
    thx_series *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    s->v = thx_calloc(ctx, n_rows * n_frames, sizeof *s->v);
    s->time = thx_malloc(ctx, (n_frames ? n_frames : 1) * sizeof *s->time);
    if (!s->v || !s->time) {
        thx_series_destroy(&s);
        return THX_ENOMEM;
    }
    s->n_rows = n_rows;
    s->n_frames = n_frames;
    for (size_t f = 0; f < n_frames; f++) s->time[f] = (double)f;
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    *out = s;
    return THX_OK;
}

void thx_series_destroy(thx_series **s)
{
    if (!s || !*s) return;
    free((*s)->v);
    free((*s)->time);
    for (size_t k = 0; k < (*s)->n_fids; k++) free((*s)->fids[k].v);
    free((*s)->fids);
    for (size_t k = 0; k < (*s)->n_fields; k++) free((*s)->fields[k].data);
    free((*s)->fields);
    free(*s);
    *s = NULL;
}

size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame)
{
    size_t n = s->n_rows * s->n_frames, count = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(s->v[i])) {
            if (count++ == 0) first = i;
        }
    if (count && s->n_rows) {
        if (row) *row = first % s->n_rows;
        if (frame) *frame = first / s->n_rows;
    }
    return count;
}

thx_status thx_series_validate(thx_ctx *ctx, const thx_series *s, const char *path)
{
    if (!s || !s->v || !s->time) return thx_error(ctx, THX_EINPUT, "%s: no series (NULL values or time)", path);
    if (s->n_rows == 0 || s->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "%s: empty series (%zu rows x %zu frames; at least 1 x 1 needed)", path,
                         s->n_rows, s->n_frames);
    if (!memchr(s->unit, '\0', sizeof s->unit) || !memchr(s->time_unit, '\0', sizeof s->time_unit) ||
        !memchr(s->label, '\0', sizeof s->label))
        return thx_error(ctx, THX_EINPUT, "%s: unit, time_unit or label is not NUL-terminated", path);
    for (size_t f = 0; f < s->n_frames; f++) {
        if (!isfinite(s->time[f]))
            return thx_error(ctx, THX_EINPUT, "%s: time of frame %zu is %g (times must be finite)", path, f + 1,
                             s->time[f]);
        if (f > 0 && !(s->time[f] > s->time[f - 1]))
            return thx_error(ctx, THX_EINPUT,
                             "%s: time of frame %zu (%.17g) is not after that of frame %zu (%.17g): "
                             "times must increase",
                             path, f + 1, s->time[f], f, s->time[f - 1]);
    }
    return THX_OK;
}

thx_status thx_series_add_fiducial(thx_ctx *ctx, thx_series *s, int type, int fidset, size_t n, const double *v)
{
    if (n != 1 && n != s->n_rows)
        return thx_error(ctx, THX_EINPUT, "a fiducial has %zu values: one, or one per row (%zu), are needed", n,
                         s->n_rows);
    double *c = thx_malloc(ctx, n * sizeof *c);
    if (!c) return THX_ENOMEM;
    thx_fiducial *f = thx_realloc(ctx, s->fids, (s->n_fids + 1) * sizeof *f);
    if (!f) {
        free(c);
        return THX_ENOMEM;
    }
    memcpy(c, v, n * sizeof *c);
    s->fids = f;
    f[s->n_fids++] = (thx_fiducial){.type = type, .fidset = fidset, .n = n, .v = c};
    return THX_OK;
}

size_t thx_field_class_size(thx_field_class c)
{
    switch (c) {
    case THX_FIELD_DOUBLE: case THX_FIELD_INT64: case THX_FIELD_UINT64: return 8;
    case THX_FIELD_SINGLE: case THX_FIELD_INT32: case THX_FIELD_UINT32: return 4;
    case THX_FIELD_INT16: case THX_FIELD_UINT16: return 2;
    case THX_FIELD_INT8: case THX_FIELD_UINT8: return 1;
    default: return 0;
    }
}

thx_status thx_series_add_field(thx_ctx *ctx, thx_series *s, const char *name, thx_field_class cls,
                                const size_t dims[2], const void *data, size_t nbytes)
{
    if (strlen(name) >= sizeof s->fields[0].name)
        return thx_error(ctx, THX_EINPUT, "field name '%.40s...' is longer than %zu bytes", name,
                         sizeof s->fields[0].name - 1);
    size_t es = thx_field_class_size(cls);
    if (es && dims[1] && dims[0] > SIZE_MAX / es / dims[1])
        return thx_error(ctx, THX_EINPUT, "field '%s': %zu x %zu elements is too large", name, dims[0], dims[1]);
    if (es && nbytes != es * dims[0] * dims[1])
        return thx_error(ctx, THX_EINTERNAL, "field '%s': %zu bytes for %zu x %zu elements of %zu bytes", name,
                         nbytes, dims[0], dims[1], es);
    void *c = NULL;
    if (data && nbytes) {
        c = thx_malloc(ctx, nbytes);
        if (!c) return THX_ENOMEM;
        memcpy(c, data, nbytes);
    }
    thx_series_field *f = thx_realloc(ctx, s->fields, (s->n_fields + 1) * sizeof *f);
    if (!f) {
        free(c);
        return THX_ENOMEM;
    }
    s->fields = f;
    thx_series_field *d = &f[s->n_fields++];
    memset(d, 0, sizeof *d);
    snprintf(d->name, sizeof d->name, "%s", name);
    d->cls = cls;
    d->dims[0] = dims[0], d->dims[1] = dims[1];
    d->data = c;
    d->nbytes = c ? nbytes : 0;
    return THX_OK;
}

const thx_series_field *thx_series_field_get(const thx_series *s, const char *name)
{
    for (size_t k = 0; k < s->n_fields; k++)
        if (!strcmp(s->fields[k].name, name)) return &s->fields[k];
    return NULL;
}

/* map3d's fiducial names (thirdparty/fi/fi.c) and its manual's aliases (doc/manual/input.tex). */
static const struct { const char *name; int type; } fid_names[] = {
    {"pon", 0},       {"poff", 1},      {"qon", 2},        {"rpeak", 3},    {"soff", 4},       {"stoff", 5},
    {"tpeak", 6},     {"toff", 7},      {"actplus", 8},    {"actminus", 9}, {"act", 10},       {"recplus", 11},
    {"recminus", 12}, {"rec", 13},      {"ref", 14},       {"jpt", 15},     {"baseline", 16},  {"subseries", 17},
    {"pacing", 30},
    /* aliases (never returned as names) */
    {"pstart", 0},    {"pend", 1},      {"qrsstart", 2},   {"qrson", 2},    {"qrspeak", 3},    {"qrsend", 4},
    {"qrsoff", 4},    {"tstart", 5},    {"ton", 5},        {"reference", 14}, {"jpoint", 15},  {"activation", 10},
    {"recovery", 13},
};

const char *thx_fiducial_type_name(int type)
{
    for (size_t k = 0; k < 19; k++)
        if (fid_names[k].type == type) return fid_names[k].name;
    return NULL;
}

int thx_fiducial_type_parse(const char *name)
{
    for (size_t k = 0; k < sizeof fid_names / sizeof fid_names[0]; k++)
        if (!strcasecmp(fid_names[k].name, name)) return fid_names[k].type;
    return -1;
}
