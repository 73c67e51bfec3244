/*
 * Saving an edit session's model (thorax/edit/edit.h), issue 24: the model keeps what the session
 * did not make.
 *
 *  - The volume mesh (volume.pts, volume.tet, the NAME.vmap node tables, model.json's "volume" and
 *    "regions") is held apart from the edited model while the session runs. A save writes it back
 *    whenever the surfaces are still those it was built on, node for node and triangle for
 *    triangle (no edit, or every edit undone); otherwise the model is written without it.
 *  - Saved in place (into the directory the session was opened on), the model keeps the folders
 *    other commands wrote into it (the electrodes of thorax electrodes), and a mesh the edits made
 *    stale is moved aside, never deleted: its files are linked (or copied) into a sibling
 *    DIR.mesh-before-edit (-2, -3, ... when taken) before the new model replaces the old one;
 *    thx_edit_session_save_note says where, and how to mesh again.
 *  - The replacement is thx_outdir's: the new model is built whole in a sibling, then swapped in;
 *    a failure leaves the old model as it was.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "edit/edit_impl.h"
#include "thorax/core/fileio.h"
#include "thorax/io/model_dir.h"

thx_status edit_keep_volume(thx_ctx *ctx, thx_edit_session *s)
{
    thx_model *m = s->m;
    s->mesh_surf = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *s->mesh_surf);
    if (!s->mesh_surf) return THX_ENOMEM;
    for (size_t k = 0; k < m->n_surfaces; k++) {
        const thx_surface *a = m->surf[k];
        thx_surface *b = NULL;
        THX_CHECK(thx_surface_create(ctx, a->name, a->role, &b));
        s->mesh_surf[s->n_mesh_surf++] = b;
        b->xyz = thx_malloc(ctx, (3 * a->n_nodes + 1) * sizeof *b->xyz);
        b->tri = thx_malloc(ctx, (3 * a->n_tris + 1) * sizeof *b->tri);
        if (!b->xyz || !b->tri) return THX_ENOMEM;
        b->n_nodes = a->n_nodes;
        b->n_tris = a->n_tris;
        if (a->n_nodes) memcpy(b->xyz, a->xyz, 3 * a->n_nodes * sizeof *b->xyz);
        if (a->n_tris) memcpy(b->tri, a->tri, 3 * a->n_tris * sizeof *b->tri);
    }
    s->kept_volume = m->volume;
    m->volume = NULL;
    return THX_OK;
}

void edit_kept_free(thx_edit_session *s)
{
    for (size_t k = 0; k < s->n_mesh_surf; k++) thx_surface_destroy(&s->mesh_surf[k]);
    free(s->mesh_surf);
    s->mesh_surf = NULL;
    s->n_mesh_surf = 0;
    thx_volume_destroy(&s->kept_volume);
}

/* The surfaces are those the kept mesh was built on: the same names, nodes and triangles, bit for bit. */
static int mesh_surfaces_same(const thx_edit_session *s)
{
    const thx_model *m = s->m;
    if (m->n_surfaces != s->n_mesh_surf) return 0;
    for (size_t k = 0; k < m->n_surfaces; k++) {
        const thx_surface *a = m->surf[k], *b = s->mesh_surf[k];
        if (strcmp(a->name, b->name) || a->n_nodes != b->n_nodes || a->n_tris != b->n_tris) return 0;
        if (a->n_nodes && memcmp(a->xyz, b->xyz, 3 * a->n_nodes * sizeof *a->xyz)) return 0;
        if (a->n_tris && memcmp(a->tri, b->tri, 3 * a->n_tris * sizeof *a->tri)) return 0;
    }
    return 1;
}

/* The same directory (device and inode). */
static int same_dir(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* dst as a hard link to src, or a copy of its bytes where links are refused. */
static thx_status copy_file(thx_ctx *ctx, const char *src, const char *dst)
{
    if (link(src, dst) == 0) return THX_OK;
    int in = open(src, O_RDONLY | O_CLOEXEC);
    if (in < 0) return thx_error(ctx, THX_EIO, "%s: %s", src, strerror(errno));
    int out = open(dst, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (out < 0) {
        int e = errno;
        close(in);
        return thx_error(ctx, THX_EIO, "%s: %s", dst, strerror(e));
    }
    char buf[1 << 16];
    ssize_t n;
    thx_status st = THX_OK;
    while ((n = read(in, buf, sizeof buf)) > 0)
        for (ssize_t w = 0; w < n && st == THX_OK;) {
            ssize_t k = write(out, buf + w, (size_t)(n - w));
            if (k < 0) st = thx_error(ctx, THX_EIO, "%s: %s", dst, strerror(errno));
            else w += k;
        }
    if (n < 0 && st == THX_OK) st = thx_error(ctx, THX_EIO, "%s: %s", src, strerror(errno));
    close(in);
    if (close(out) != 0 && st == THX_OK) st = thx_error(ctx, THX_EIO, "%s: %s", dst, strerror(errno));
    return st;
}

/* The folder src (files and folders, no links) into dst, created. */
static thx_status copy_tree(thx_ctx *ctx, const char *src, const char *dst)
{
    if (mkdir(dst, 0755) != 0) return thx_error(ctx, THX_EIO, "%s: cannot create: %s", dst, strerror(errno));
    DIR *d = opendir(src);
    if (!d) return thx_error(ctx, THX_EIO, "%s: cannot read: %s", src, strerror(errno));
    thx_status st = THX_OK;
    struct dirent *e;
    while (st == THX_OK && (e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char a[PATH_MAX], b[PATH_MAX];
        struct stat sb;
        if ((size_t)snprintf(a, sizeof a, "%s/%s", src, e->d_name) >= sizeof a ||
            (size_t)snprintf(b, sizeof b, "%s/%s", dst, e->d_name) >= sizeof b) {
            st = thx_error(ctx, THX_EIO, "%s/%s: path too long", src, e->d_name);
            break;
        }
        if (lstat(a, &sb) != 0) st = thx_error(ctx, THX_EIO, "%s: %s", a, strerror(errno));
        else if (S_ISDIR(sb.st_mode)) st = copy_tree(ctx, a, b);
        else if (S_ISREG(sb.st_mode)) st = copy_file(ctx, a, b);
    }
    closedir(d);
    return st;
}

/* The stale mesh's files (volume.pts, volume.tet, the node tables, and model.json that describes
 * them) linked into a new sibling of dir; its path into aside. */
static thx_status move_mesh_aside(thx_ctx *ctx, const thx_edit_session *s, const char *dir, char *aside, size_t cap)
{
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    int made = 0;
    for (int k = 1; k <= 99 && !made; k++) {
        if (k == 1) snprintf(aside, cap, "%.*s.mesh-before-edit", (int)n, dir);
        else snprintf(aside, cap, "%.*s.mesh-before-edit-%d", (int)n, dir, k);
        if (mkdir(aside, 0755) == 0) made = 1;
        else if (errno != EEXIST) return thx_error(ctx, THX_EIO, "%s: cannot create: %s", aside, strerror(errno));
    }
    if (!made) return thx_error(ctx, THX_EIO, "%.*s.mesh-before-edit-99: 99 such folders are there already", (int)n, dir);
    const char *fixed[] = {"volume.pts", "volume.tet", "volume.steiner", THX_MODEL_MANIFEST};
    for (size_t k = 0; k < 4 + s->n_mesh_surf; k++) {
        char name[96], a[PATH_MAX], b[PATH_MAX];
        if (k < 4) snprintf(name, sizeof name, "%s", fixed[k]);
        else snprintf(name, sizeof name, "%s.vmap", s->mesh_surf[k - 4]->name);
        if ((size_t)snprintf(a, sizeof a, "%.*s/%s", (int)n, dir, name) >= sizeof a ||
            (size_t)snprintf(b, sizeof b, "%s/%s", aside, name) >= sizeof b)
            return thx_error(ctx, THX_EIO, "%s/%s: path too long", aside, name);
        if (access(a, F_OK) != 0) continue;
        THX_CHECK(copy_file(ctx, a, b));
    }
    return THX_OK;
}

/* Writes the model into a new sibling of dir, with dir's folders (other commands' outputs) copied
 * in, then swaps it in for dir. */
static thx_status save_in_place(thx_ctx *ctx, thx_edit_session *s, const char *dir, int stale)
{
    thx_outdir od, staging;
    THX_CHECK(thx_outdir_claim(ctx, &od, dir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, NULL, 0));
    memset(&staging, 0, sizeof staging);
    if ((size_t)snprintf(staging.tmp, sizeof staging.tmp, "%s.saveXXXXXX", od.dir) >= sizeof od.tmp || !mkdtemp(staging.tmp))
        return thx_error(ctx, THX_EIO, "%s: cannot create a temporary directory beside it: %s", od.dir, strerror(errno));
    thx_status st = thx_model_write(ctx, s->m, staging.tmp);
    DIR *d = st == THX_OK ? opendir(od.dir) : NULL;
    if (st == THX_OK && !d) st = thx_error(ctx, THX_EIO, "%s: cannot read: %s", od.dir, strerror(errno));
    struct dirent *e;
    while (d && st == THX_OK && (e = readdir(d))) {
        char a[PATH_MAX], b[PATH_MAX];
        struct stat sb;
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        if ((size_t)snprintf(a, sizeof a, "%s/%s", od.dir, e->d_name) >= sizeof a ||
            (size_t)snprintf(b, sizeof b, "%s/%s", staging.tmp, e->d_name) >= sizeof b) {
            st = thx_error(ctx, THX_EIO, "%s/%s: path too long", od.dir, e->d_name);
            break;
        }
        /* a folder in a model is another command's output with its own manifest (thx_outdir) */
        if (lstat(a, &sb) == 0 && S_ISDIR(sb.st_mode) && access(b, F_OK) != 0) st = copy_tree(ctx, a, b);
    }
    if (d) closedir(d);
    char aside[PATH_MAX] = "";
    if (st == THX_OK && stale) st = move_mesh_aside(ctx, s, od.dir, aside, sizeof aside);
    if (st != THX_OK) {
        thx_outdir_abort(&staging);
        return st;
    }
    memcpy(od.tmp, staging.tmp, sizeof od.tmp);
    THX_CHECK(thx_outdir_commit(ctx, &od));
    if (stale)
        snprintf(s->save_note, sizeof s->save_note,
                 "the edits changed the surfaces its volume mesh was built on: the mesh is moved aside to %.300s (with the "
                 "model.json that describes it), not deleted; mesh again: thorax mesh %.300s -o MESHED",
                 aside, od.dir);
    return THX_OK;
}

thx_status thx_edit_session_save(thx_ctx *ctx, thx_edit_session *s, const char *dir)
{
    s->save_note[0] = '\0';
    THX_CHECK(edit_session_set_log(ctx, s));
    int keep = s->kept_volume && mesh_surfaces_same(s);
    int in_place = s->source_dir[0] && same_dir(dir, s->source_dir);
    if (!in_place) THX_CHECK(edit_rebase_contours(ctx, s, dir));
    if (keep) s->m->volume = s->kept_volume; /* lent for the write */
    thx_status st = in_place ? save_in_place(ctx, s, dir, s->kept_volume && !keep) : thx_model_write(ctx, s->m, dir);
    if (keep) s->m->volume = NULL;
    if (st == THX_OK && s->kept_volume && !keep && !in_place)
        snprintf(s->save_note, sizeof s->save_note,
                 "the edits changed the surfaces the volume mesh of %.200s was built on: %.200s is saved without one (%.200s "
                 "keeps it); mesh again: thorax mesh %.200s -o MESHED",
                 s->source_dir[0] ? s->source_dir : "the model", dir, s->source_dir[0] ? s->source_dir : "the model", dir);
    return st;
}

thx_status thx_edit_session_save_claimed(thx_ctx *ctx, thx_edit_session *s, thx_outdir *od)
{
    s->save_note[0] = '\0';
    THX_CHECK(edit_session_set_log(ctx, s));
    int keep = s->kept_volume && mesh_surfaces_same(s);
    if (keep) s->m->volume = s->kept_volume;
    thx_status st = thx_model_write_claimed(ctx, s->m, od);
    if (keep) s->m->volume = NULL;
    return st;
}

const char *thx_edit_session_save_note(const thx_edit_session *s) { return s->save_note; }

int thx_edit_session_has_mesh(const thx_edit_session *s) { return s->kept_volume != NULL; }
