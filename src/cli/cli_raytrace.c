/*
 * The ray tracer's options (RaySpray, thorax/raytrace/raytrace.h) for thorax render, animate and
 * trace: the renderer, lights, materials by surface name, samples, ambient occlusion, depth, the
 * volume, motion blur.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli_raytrace.h"

/* "X,Y,Z" -> v; 0, or -1 */
static int vec3(const char *s, double v[3])
{
    char *end;
    for (int k = 0; k < 3; k++) {
        v[k] = strtod(s, &end);
        if (end == s || !isfinite(v[k]) || (k < 2 && *end != ',') || (k == 2 && *end && *end != ':')) return -1;
        s = end + (k < 2);
    }
    return 0;
}

/* head[:I], point:X,Y,Z[:I], directional:DX,DY,DZ[:I], area:X,Y,Z:UX,UY,UZ:VX,VY,VZ[:I] */
static int parse_light(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    thx_raytrace_opts *rt = &o->p.rt;
    static const char *usage = "--light head[:I], point:X,Y,Z[:I], directional:DX,DY,DZ[:I] or area:X,Y,Z:UX,UY,UZ:VX,VY,VZ[:I] "
                               "(model mm; I the intensity, 1)";
    if (rt->n_lights >= THX_RAYTRACE_MAX_LIGHTS) return cli_usage_error(o->cmd, "--light: at most %d lights", THX_RAYTRACE_MAX_LIGHTS);
    thx_light L;
    memset(&L, 0, sizeof L);
    L.intensity = 1;
    L.shadows = 1;
    const char *p = strchr(v, ':'), *rest = p ? p + 1 : "";
    size_t kl = p ? (size_t)(p - v) : strlen(v);
    int fields = 0;
    if (kl == 4 && !strncmp(v, "head", 4)) { L.kind = THX_LIGHT_HEAD; L.shadows = 0; }
    else if (kl == 5 && !strncmp(v, "point", 5)) { L.kind = THX_LIGHT_POINT; fields = 1; }
    else if (kl == 11 && !strncmp(v, "directional", 11)) { L.kind = THX_LIGHT_DIRECTIONAL; fields = 1; }
    else if (kl == 4 && !strncmp(v, "area", 4)) { L.kind = THX_LIGHT_AREA; fields = 3; }
    else return cli_usage_error(o->cmd, "%s", usage);
    double *dst[3] = {L.kind == THX_LIGHT_DIRECTIONAL ? L.dir : L.pos, L.u, L.v};
    for (int f = 0; f < fields; f++) {
        if (!*rest || vec3(rest, dst[f])) return cli_usage_error(o->cmd, "%s: '%s'", usage, v);
        const char *c = strchr(rest, ':');
        rest = c ? c + 1 : "";
    }
    if (*rest) {
        char *end;
        L.intensity = strtod(rest, &end);
        if (*end || !(L.intensity > 0) || !isfinite(L.intensity)) return cli_usage_error(o->cmd, "%s: '%s'", usage, v);
    }
    if (L.kind == THX_LIGHT_DIRECTIONAL && L.dir[0] == 0 && L.dir[1] == 0 && L.dir[2] == 0)
        return cli_usage_error(o->cmd, "--light directional: a direction, not zero");
    rt->lights[rt->n_lights++] = L;
    return 0;
}

/* NAME=KIND[:VALUE][+KIND[:VALUE]]... with KIND glass[:IOR], mirror[:R], transparent[:T], grid[:MM],
 * checker[:MM] */
static int parse_material(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    thx_picture_opts *p = &o->p;
    static const char *usage = "--material NAME=KIND[:VALUE][+KIND[:VALUE]...] with KIND glass[:IOR, 1.5], mirror[:REFLECTANCE, 0.8], "
                               "transparent[:T, 0.6], grid[:MM, 10] or checker[:MM, 10]";
    const char *eq = strchr(v, '=');
    if (!eq || eq == v || (size_t)(eq - v) >= sizeof p->rt_mat[0].name) return cli_usage_error(o->cmd, "%s", usage);
    if (p->n_rt_mat >= THX_PICTURE_MAX) return cli_usage_error(o->cmd, "--material: at most %d", THX_PICTURE_MAX);
    thx_raytrace_material m = {.ior = 1, .texture_mm = 10};
    char buf[256];
    snprintf(buf, sizeof buf, "%s", eq + 1);
    for (char *tok = strtok(buf, "+"); tok; tok = strtok(NULL, "+")) {
        char *c = strchr(tok, ':');
        double x = NAN;
        if (c) {
            *c = '\0';
            char *end;
            x = strtod(c + 1, &end);
            if (*end || !isfinite(x)) return cli_usage_error(o->cmd, "%s: '%s'", usage, v);
        }
        if (!strcmp(tok, "glass")) {
            m.transmit = 0.9;
            m.ior = c ? x : 1.5;
            if (!(m.ior >= 1 && m.ior <= 3)) return cli_usage_error(o->cmd, "--material glass:IOR: 1 to 3");
        } else if (!strcmp(tok, "mirror")) {
            m.reflect = c ? x : 0.8;
        } else if (!strcmp(tok, "transparent")) {
            m.transmit = c ? x : 0.6;
        } else if (!strcmp(tok, "grid") || !strcmp(tok, "checker")) {
            m.texture = tok[0] == 'g' ? 1 : 2;
            m.texture_mm = c ? x : 10;
            if (!(m.texture_mm > 0)) return cli_usage_error(o->cmd, "--material %s:MM: above 0", tok);
        } else {
            return cli_usage_error(o->cmd, "%s: '%s'", usage, v);
        }
    }
    if (!(m.reflect >= 0 && m.transmit >= 0 && m.reflect + m.transmit <= 1))
        return cli_usage_error(o->cmd, "--material '%s': reflectance and transmission from 0 to 1, together at most 1", v);
    snprintf(p->rt_mat[p->n_rt_mat].name, sizeof p->rt_mat[0].name, "%.*s", (int)(eq - v), v);
    p->rt_mat[p->n_rt_mat++].m = m;
    return 0;
}

static int parse_volume(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    if (strcmp(v, "potential") && strcmp(v, "current")) return cli_usage_error(o->cmd, "--volume potential or --volume current");
    o->p.volume_render = v;
    return 0;
}

/* T:A[,T:A...], T ascending in [0, 1], A >= 0 */
static int parse_opacity(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    thx_picture_opts *p = &o->p;
    static const char *usage = "--volume-opacity T:A[,T:A...]: points of the opacity over the colour scale, T from 0 to 1 "
                               "ascending, A >= 0 (e.g. 0:1,0.4:0,0.6:0,1:1)";
    p->n_volume_opacity = 0;
    const char *s = v;
    while (*s) {
        char *end;
        double t = strtod(s, &end);
        if (end == s || *end != ':') return cli_usage_error(o->cmd, "%s", usage);
        s = end + 1;
        double a = strtod(s, &end);
        if (end == s || (*end && *end != ',')) return cli_usage_error(o->cmd, "%s", usage);
        s = *end ? end + 1 : end;
        int n = p->n_volume_opacity;
        if (n >= THX_RAYTRACE_MAX_OPACITY || !(t >= 0 && t <= 1) || !(a >= 0) || !isfinite(a) || (n && t < p->volume_opacity[n - 1][0]))
            return cli_usage_error(o->cmd, "%s", usage);
        p->volume_opacity[n][0] = t;
        p->volume_opacity[n][1] = a;
        p->n_volume_opacity++;
    }
    if (!p->n_volume_opacity) return cli_usage_error(o->cmd, "%s", usage);
    return 0;
}

static const cli_choice renderers[] = {{"gl", 0}, {"trace", 1}, {NULL, 0}};

size_t raytrace_options(cli_opt *t, ropts *o)
{
    size_t n = 0;
    t[n++] = (cli_opt){.name = "--renderer", .type = CLI_CHOICE, .choices = renderers, .i = &o->p.renderer,
                       .help = "gl: OpenGL (the paper's HiPPR); trace: the ray tracer (RaySpray, Embree): shadows, "
                               "reflection, refraction, ambient occlusion; the same scene and colours"};
    t[n++] = (cli_opt){.name = "--light", .type = CLI_STRING, .meta = "SPEC", .flags = CLI_REPEAT, .fn = parse_light,
                       .help = "trace: a light, head[:I] (at the eye), point:X,Y,Z[:I], directional:DX,DY,DZ[:I] or "
                               "area:X,Y,Z:UX,UY,UZ:VX,VY,VZ[:I] (a rectangle: soft shadows); all but head cast shadows "
                               "(repeat for more; none: the headlight alone)"};
    t[n++] = (cli_opt){.name = "--material", .type = CLI_STRING, .meta = "NAME=KIND", .flags = CLI_REPEAT, .fn = parse_material,
                       .help = "trace: a surface's material, KIND[:VALUE] joined by +: glass[:IOR] (refracts), "
                               "mirror[:R], transparent[:T], grid[:MM], checker[:MM] (e.g. torso=glass, heart=mirror:0.3)"};
    t[n++] = (cli_opt){.name = "--samples", .type = CLI_INT, .meta = "N", .i = &o->p.rt.samples, .rule = CLI_GE | CLI_LE,
                       .lo = 1, .hi = 16, .bad = "--samples: 1 to 16",
                       .help = "trace: N x N jittered samples a pixel (anti-aliasing, soft shadows)"};
    t[n++] = (cli_opt){.name = "--ao", .type = CLI_INT, .meta = "N", .i = &o->p.rt.ao_samples, .rule = CLI_GE | CLI_LE,
                       .lo = 0, .hi = 256, .bad = "--ao: 0 to 256",
                       .help = "trace: ambient occlusion, N rays a hit within --ao-distance (0: none)"};
    t[n++] = (cli_opt){.name = "--ao-distance", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->p.rt.ao_distance,
                       .rule = CLI_GT | CLI_FINITE, .lo = 0, .bad = "--ao-distance: above 0",
                       .help = "trace: how far occluders count for ambient occlusion"};
    t[n++] = (cli_opt){.name = "--depth", .type = CLI_INT, .meta = "N", .i = &o->p.rt.max_depth, .rule = CLI_GE | CLI_LE,
                       .lo = 0, .hi = 32, .bad = "--depth: 0 to 32",
                       .help = "trace: reflection and refraction bounces at most"};
    t[n++] = (cli_opt){.name = "--environment", .type = CLI_STRING, .meta = "PNG|sky", .s = &o->p.environment,
                       .help = "trace: what rays leaving the scene see, the background and reflections: an "
                               "equirectangular PNG (longitude across, superior at the top) or sky (a gradient)"};
    t[n++] = (cli_opt){.name = "--volume", .type = CLI_STRING, .meta = "FIELD", .fn = parse_volume,
                       .help = "trace: the field rendered inside the torso by emission and absorption (needs --solution "
                               "with volume potentials): potential (linear in each tetrahedron, the colour scale's) or "
                               "current (|J| per tetrahedron, viridis), each over the frame's own range; --colorbar adds its bar"};
    t[n++] = (cli_opt){.name = "--volume-opacity", .type = CLI_STRING, .meta = "T:A,...", .fn = parse_opacity,
                       .help = "trace: the volume's opacity over its colour scale, points T:A (default: clear at the "
                               "middle, opaque at both ends; current: rising from 0)"};
    t[n++] = (cli_opt){.name = "--volume-density", .type = CLI_REAL, .meta = "PER_MM", .unit = "1/mm", .d = &o->p.volume_density,
                       .rule = CLI_GT | CLI_FINITE, .lo = 0, .bad = "--volume-density: above 0", .def = "0.02",
                       .help = "trace: the volume's extinction per mm at opacity 1"};
    t[n++] = (cli_opt){.name = "--motion-blur", .type = CLI_REAL, .meta = "S", .d = &o->p.rt.shutter,
                       .rule = CLI_GE | CLI_LE | CLI_FINITE, .lo = 0, .hi = 1, .bad = "--motion-blur: 0 to 1", .def = "0",
                       .help = "trace: motion blur towards the next frame, S the shutter (0 to 1 of the frame interval; "
                               "0: none): each sample sees the camera and the surfaces' values at its own time (the "
                               "volume unblurred); animate: the flight's next camera (--keys); trace: --frame K "
                               "blurred towards K + 1"};
    return n;
}
