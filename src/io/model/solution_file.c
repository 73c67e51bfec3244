/* A forward solution's model and volume potentials (thorax/io/solution_file.h). */
#include "thorax/io/solution_file.h"

#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/model/volume.h"

thx_status thx_solution_read_volume(thx_ctx *ctx, const char *dir, thx_model **model, thx_series **volume,
                                    char *model_dir, size_t model_dir_size)
{
    *model = NULL;
    *volume = NULL;
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/solution.json", dir);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(j, "format");
    const cJSON *mo = cJSON_GetObjectItemCaseSensitive(j, "model");
    const cJSON *files = cJSON_GetObjectItemCaseSensitive(j, "files");
    const cJSON *vo = cJSON_GetObjectItemCaseSensitive(files, "volume");
    thx_status st = THX_OK;
    if (!j || !cJSON_IsString(fmt) || strcmp(fmt->valuestring, "thorax-solution") != 0)
        st = thx_error(ctx, THX_EINPUT, "%s: not a thorax solution (no \"format\": \"thorax-solution\")", path);
    else if (!cJSON_IsString(mo))
        st = thx_error(ctx, THX_EINPUT, "%s: no \"model\" (the model directory)", path);
    else if (!cJSON_IsString(vo) || strchr(vo->valuestring, '/'))
        st = thx_error(ctx, THX_EINPUT, "%s: no volume potentials (\"files\": \"volume\"): run thorax forward ... --volume",
                       path);
    if (st == THX_OK) {
        if (model_dir) snprintf(model_dir, model_dir_size, "%s", mo->valuestring);
        st = thx_model_read(ctx, mo->valuestring, model);
    }
    if (st == THX_OK && !(*model)->volume)
        st = thx_error(ctx, THX_EINPUT, "%s: the solution's model %s has no volume mesh", path, mo->valuestring);
    if (st == THX_OK) {
        snprintf(path, sizeof path, "%s/%s", dir, vo->valuestring);
        st = thx_series_read(ctx, path, THX_SERIES_AUTO, volume);
    }
    if (st == THX_OK && (*volume)->n_rows != (*model)->volume->n_nodes)
        st = thx_error(ctx, THX_EINPUT, "%s: %zu rows, the model's volume mesh (%s) has %zu nodes", path,
                       (*volume)->n_rows, mo->valuestring, (*model)->volume->n_nodes);
    cJSON_Delete(j);
    if (st != THX_OK) {
        thx_model_destroy(model);
        thx_series_destroy(volume);
    }
    return st;
}

thx_status thx_solution_domain(thx_ctx *ctx, const char *dir, const thx_volume *v, unsigned char *use)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/solution.json", dir);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    const cJSON *pr = cJSON_GetObjectItemCaseSensitive(j, "problem");
    thx_status st = THX_OK;
    int whole = 0;
    if (!cJSON_IsString(pr))
        st = thx_error(ctx, THX_EINPUT, "%s: no \"problem\"", path);
    else if (!strcmp(pr->valuestring, "dipoles") || !strcmp(pr->valuestring, "defibrillation"))
        whole = 1;
    else if (strcmp(pr->valuestring, "epicardial") && strcmp(pr->valuestring, "transfer matrix (epicardial)"))
        st = thx_error(ctx, THX_EINPUT, "%s: unknown problem \"%s\"", path, pr->valuestring);
    cJSON_Delete(j);
    if (st != THX_OK) return st;
    for (size_t r = 0; r < v->n_regions; r++) use[r] = (unsigned char)(whole || strcmp(v->regions[r].name, "heart") != 0);
    return THX_OK;
}
