/* A volume check's verdict kept in model.json (thorax/check/verdict.h). */
#include <cjson/cJSON.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/check/verdict.h"
#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"

static const char k_tag[] = "thorax volume verdict v1";

static int plain_name(const char *s) { return s && s[0] && !strchr(s, '/') && strcmp(s, ".") && strcmp(s, ".."); }

/* model.json parsed into *out (an object), or an error naming the file. */
static thx_status read_manifest(thx_ctx *ctx, const char *dir, char *path, size_t path_n, cJSON **out)
{
    *out = NULL;
    if (snprintf(path, path_n, "%s/model.json", dir) >= (int)path_n)
        return thx_error(ctx, THX_EINPUT, "%s: path too long", dir);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *root = cJSON_ParseWithLength(text, len);
    free(text);
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return thx_error(ctx, THX_EINPUT, "%s: not a JSON object", path);
    }
    *out = root;
    return THX_OK;
}

/* One named file's bytes into the hash, with its name and length. */
static thx_status hash_file(thx_ctx *ctx, thx_sha256_ctx *h, const char *dir, const char *name)
{
    if (!plain_name(name)) return thx_error(ctx, THX_EINPUT, "%s/model.json: \"%s\" is not a file name", dir, name ? name : "");
    char path[4200];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path)
        return thx_error(ctx, THX_EINPUT, "%s: path too long", dir);
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: %s", path, strerror(errno));
    thx_sha256_update(h, name, strlen(name) + 1);
    static const size_t B = (size_t)1 << 20;
    unsigned char *buf = malloc(B);
    if (!buf) {
        fclose(f);
        return THX_ENOMEM;
    }
    uint64_t total = 0;
    size_t got;
    while ((got = fread(buf, 1, B, f)) > 0) {
        thx_sha256_update(h, buf, got);
        total += got;
    }
    int bad = ferror(f);
    fclose(f);
    free(buf);
    if (bad) return thx_error(ctx, THX_EIO, "%s: read error", path);
    thx_sha256_update(h, &total, sizeof total);
    return THX_OK;
}

/* The digest of root (its volume.check already detached) and the files it names. */
static thx_status digest_of(thx_ctx *ctx, const char *dir, const cJSON *root, char hex[65])
{
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, k_tag, sizeof k_tag);
    char *canon = cJSON_PrintUnformatted(root);
    if (!canon) return THX_ENOMEM;
    thx_sha256_update(&h, canon, strlen(canon) + 1);
    free(canon);
    static const char *const skeys[] = {"pts", "fac", "vmap"};
    const cJSON *s;
    cJSON_ArrayForEach(s, cJSON_GetObjectItemCaseSensitive(root, "surfaces"))
    for (size_t k = 0; k < 3; k++) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(s, skeys[k]);
        if (cJSON_IsString(v)) THX_CHECK(hash_file(ctx, &h, dir, v->valuestring));
    }
    static const char *const vkeys[] = {"pts", "tet", "steiner"};
    const cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    for (size_t k = 0; k < 3 && vo; k++) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(vo, vkeys[k]);
        if (cJSON_IsString(v)) THX_CHECK(hash_file(ctx, &h, dir, v->valuestring));
    }
    unsigned char d[32];
    thx_sha256_final(&h, d);
    for (int i = 0; i < 32; i++) snprintf(hex + 2 * i, 3, "%02x", d[i]);
    return THX_OK;
}

int thx_volume_verdict_trusted(thx_ctx *ctx, const char *dir, char *why, size_t why_n)
{
    char path[4200], hex[65];
    cJSON *root = NULL;
    if (read_manifest(ctx, dir, path, sizeof path, &root) != THX_OK) {
        snprintf(why, why_n, "%s", thx_ctx_message(ctx));
        thx_ctx_clear(ctx);
        return 0;
    }
    int ok = 0;
    cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    cJSON *c = cJSON_IsObject(vo) ? cJSON_DetachItemFromObjectCaseSensitive(vo, "check") : NULL;
    const cJSON *passed = cJSON_GetObjectItemCaseSensitive(c, "passed"), *rules = cJSON_GetObjectItemCaseSensitive(c, "rules");
    const cJSON *opts = cJSON_GetObjectItemCaseSensitive(c, "options"), *sum = cJSON_GetObjectItemCaseSensitive(c, "sha256");
    if (!c) snprintf(why, why_n, "no verdict in model.json");
    else if (!cJSON_IsTrue(passed)) snprintf(why, why_n, "the verdict in model.json is not a pass");
    else if (!cJSON_IsNumber(rules) || rules->valuedouble != THX_VOLUME_CHECK_RULES)
        snprintf(why, why_n, "the verdict was given by other rules (%g; these are %d)", cJSON_IsNumber(rules) ? rules->valuedouble : -1.0,
                 THX_VOLUME_CHECK_RULES);
    else if (!cJSON_IsString(opts) || strcmp(opts->valuestring, "default"))
        snprintf(why, why_n, "the verdict was given with other options than the default ones");
    else if (!cJSON_IsString(sum) || strlen(sum->valuestring) != 64)
        snprintf(why, why_n, "the verdict's sha256 is missing or malformed");
    else if (digest_of(ctx, dir, root, hex) != THX_OK) {
        snprintf(why, why_n, "%s", thx_ctx_message(ctx));
        thx_ctx_clear(ctx);
    } else if (strcmp(hex, sum->valuestring)) snprintf(why, why_n, "the model's files changed since its verdict");
    else ok = 1;
    cJSON_Delete(c);
    cJSON_Delete(root);
    return ok;
}

thx_status thx_volume_verdict_record(thx_ctx *ctx, const char *dir)
{
    char path[4200], hex[65];
    cJSON *root = NULL;
    THX_CHECK(read_manifest(ctx, dir, path, sizeof path, &root));
    thx_status st = THX_OK;
    char *text = NULL;
    cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    if (!cJSON_IsObject(vo)) {
        st = thx_error(ctx, THX_EINPUT, "%s: no \"volume\" to record a verdict for", path);
        goto done;
    }
    cJSON_DeleteItemFromObjectCaseSensitive(vo, "check");
    THX_TRY(digest_of(ctx, dir, root, hex));
    cJSON *c = cJSON_AddObjectToObject(vo, "check");
    if (!c || !cJSON_AddBoolToObject(c, "passed", 1) || !cJSON_AddNumberToObject(c, "rules", THX_VOLUME_CHECK_RULES) ||
        !cJSON_AddStringToObject(c, "options", "default") || !cJSON_AddStringToObject(c, "sha256", hex)) {
        st = THX_ENOMEM;
        goto done;
    }
    text = cJSON_Print(root);
    if (!text) {
        st = THX_ENOMEM;
        goto done;
    }
    thx_atomic_file af;
    THX_TRY(thx_atomic_open(ctx, path, &af));
    fputs(text, af.f);
    fputc('\n', af.f);
    st = thx_atomic_commit(ctx, &af);
done:
    free(text);
    cJSON_Delete(root);
    return st;
}
