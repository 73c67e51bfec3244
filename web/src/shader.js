// The surface shader: the arithmetic of `thorax render`'s (src/render/render_shaders.c, GLSL_LIGHT,
// VS_SURF and FS_SURF) in GLSL ES 3.00, so that a pixel of the page equals render's pixel.
// Variants by #define, as render's:
//   PRIM   0 triangles, 2 lines (wire): render's geometry shader GS_LINES widens each edge into a
//          screen-aligned quad; WebGL has no geometry shaders, so each edge comes as the quad's four
//          corners (its end `position`, the `other` end, and `corner`) and the vertex shader places them
//   LIGHT  0 none, 1 flat (the face normal from screen derivatives), 2 Gouraud, 3 Phong
//   DATA   1: colour by t per pixel; STYLE (thx_data_style): 0 continuous, 1 bands, 2 contours (over
//          the surface's colour), 3 bands + contours, 4 continuous + contours
// The lighting inputs are interpolated at the centroid of the covered samples (no extrapolated
// normal at a multisampled silhouette); t is not, as the contour lines need its derivatives.
import * as THREE from 'three';

const LIGHT = /* glsl */ `
uniform vec4 u_light; // ka, kd, ks, shine (render's KA, KD, KS, SHINE)
uniform int u_ortho;
// The headlight: at the eye (along the line of sight when orthographic), two-sided |n . l|.
vec2 headlight(vec3 n, vec3 eye) {
    vec3 l = u_ortho == 1 ? vec3(0.0, 0.0, 1.0) : normalize(-eye);
    float ln = length(n);
    float d = ln > 0.0 ? abs(dot(n / ln, l)) : 1.0;
    return vec2(d, pow(d, u_light.w));
}
`;

const VERTEX = /* glsl */ `
precision highp float;
precision highp int;
// three.js sets them from our camera: modelViewMatrix is render's u_view for the surfaces (their model
// matrix is the identity) and places the electrodes' and the mark's spheres.
uniform mat4 modelViewMatrix, projectionMatrix;
in vec3 position;
in vec3 normal;
in float t;
out float v_t;
#if PRIM == 2
in vec3 other;
in vec2 corner; // x: -1 at the edge's first end, +1 at its second; y: the side, -1 or +1
uniform vec2 u_vp; // the viewport in framebuffer pixels
uniform float u_lw;
#endif
#if LIGHT == 1 || LIGHT == 3
centroid out vec3 v_eye;
#endif
#if LIGHT == 3
centroid out vec3 v_nrm;
#endif
#if LIGHT == 2
centroid out vec2 v_lit;
#endif
${LIGHT}
void main() {
#if PRIM == 2
    // GS_LINES: a quad u_lw pixels wide, extended by half the width at both ends (the edges join).
    vec4 p = projectionMatrix * (modelViewMatrix * vec4(position, 1.0));
    vec4 q = projectionMatrix * (modelViewMatrix * vec4(other, 1.0));
    v_t = t;
    vec2 d = corner.x * (p.xy / p.w - q.xy / q.w) * 0.5 * u_vp; // the edge from its first end to its second
    float len = length(d);
    vec2 dir = len > 1e-4 ? d / len : vec2(1.0, 0.0);
    vec2 nrm = vec2(-dir.y, dir.x);
    vec2 px = 2.0 / u_vp;
    gl_Position = vec4(p.xy + (corner.x * dir + corner.y * nrm) * 0.5 * u_lw * px * p.w, p.zw);
    if (p.w <= 0.0 || q.w <= 0.0) gl_Position = vec4(0.0, 0.0, -2.0, 1.0); // behind the eye: not drawn
#else
    vec4 e = modelViewMatrix * vec4(position, 1.0);
    vec3 n = mat3(modelViewMatrix) * normal;
    v_t = t;
#if LIGHT == 1 || LIGHT == 3
    v_eye = e.xyz;
#endif
#if LIGHT == 3
    v_nrm = n;
#endif
#if LIGHT == 2
    v_lit = headlight(n, e.xyz);
#endif
    gl_Position = projectionMatrix * e;
#endif
}
`;

const FRAGMENT = /* glsl */ `
precision highp float;
precision highp int;
#define CONTOURS (PRIM == 0 && DATA == 1 && STYLE >= 2)
in float v_t;
#if LIGHT == 1 || LIGHT == 3
centroid in vec3 v_eye;
#endif
#if LIGHT == 3
centroid in vec3 v_nrm;
#endif
#if LIGHT == 2
centroid in vec2 v_lit;
#endif
uniform int u_nlev;
uniform float u_lw, u_cmap_n;
uniform vec4 u_color, u_nan_color, u_contour_color;
uniform sampler2D u_cmap;
out vec4 o_color;
${LIGHT}
void main() {
    float n = float(max(u_nlev, 1));
#if CONTOURS
    float f = v_t * n;
    float fw = fwidth(f);
#endif
#if LIGHT == 1
    vec3 fn = cross(dFdx(v_eye), dFdy(v_eye));
#endif
    vec4 base = u_color;
    float line = 0.0;
#if DATA == 1
    if (abs(v_t) > 2.0) base = u_nan_color; // a NaN node's flag (NAN_T) reaches here
    else {
        float tt = clamp(v_t, 0.0, 1.0);
#if STYLE == 1 || STYLE == 3
        tt = (min(floor(tt * n), n - 1.0) + 0.5) / n;
#endif
#if STYLE != 2
        base.rgb = texture(u_cmap, vec2((tt * (u_cmap_n - 1.0) + 0.5) / u_cmap_n, 0.5)).rgb;
#endif
#if CONTOURS
        float k = floor(f + 0.5);
        if (k >= 1.0 && k <= n - 1.0 && fw > 0.0) line = clamp(0.5 * u_lw - abs(f - k) / fw + 0.5, 0.0, 1.0);
#endif
    }
#endif
    vec3 rgb = base.rgb;
#if LIGHT == 1
    rgb *= u_light.x + u_light.y * headlight(fn, v_eye).x;
#elif LIGHT == 2
    rgb = rgb * (u_light.x + u_light.y * v_lit.x) + u_light.z * v_lit.y;
#elif LIGHT == 3
    vec2 l = headlight(v_nrm, v_eye);
    rgb = rgb * (u_light.x + u_light.y * l.x) + u_light.z * l.y;
#endif
#if CONTOURS
    rgb = mix(rgb, u_contour_color.rgb, line * u_contour_color.a);
#endif
    rgb = clamp(rgb, 0.0, 1.0);
    o_color = vec4(rgb * base.a, base.a); // premultiplied, as render's framebuffer
}
`;

const STYLES = { continuous: 0, bands: 1, contours: 2, 'bands+contours': 3, 'continuous+contours': 4 };

export function styleCode(name) {
    return STYLES[name] !== undefined ? STYLES[name] : 0;
}

// The colour map's table (n RGB triples) as an n x 1 RGBA texture read with linear filtering and
// no colour-space conversion (render uploads the bytes as they are).
export function colormapTexture(rgb, n) {
    const rgba = new Uint8Array(4 * n);
    for (let i = 0; i < n; i++) {
        rgba[4 * i] = rgb[3 * i];
        rgba[4 * i + 1] = rgb[3 * i + 1];
        rgba[4 * i + 2] = rgb[3 * i + 2];
        rgba[4 * i + 3] = 255;
    }
    const tex = new THREE.DataTexture(rgba, n, 1, THREE.RGBAFormat, THREE.UnsignedByteType);
    tex.colorSpace = THREE.NoColorSpace;
    tex.magFilter = THREE.LinearFilter;
    tex.minFilter = THREE.LinearFilter;
    tex.wrapS = THREE.ClampToEdgeWrapping;
    tex.wrapT = THREE.ClampToEdgeWrapping;
    tex.generateMipmaps = false;
    tex.flipY = false;
    tex.needsUpdate = true;
    return tex;
}

// A surface material: prim 0 triangles or 2 lines (wireGeometry's quads), light 0..3, data 0/1,
// style 0..4.
// opts: {color: [r, g, b, a], nan, contour, light: {ka, kd, ks, shine}, levels, lineWidth, cmap, cmapN}
export function surfaceMaterial(prim, light, data, style, opts) {
    if (!data) style = 0;
    if (prim !== 0) style = style === 2 || style === 4 ? 0 : style === 3 ? 1 : style; // lines carry no contour lines: the fill
    const L = opts.light;
    const mat = new THREE.RawShaderMaterial({
        glslVersion: THREE.GLSL3,
        vertexShader: VERTEX,
        fragmentShader: FRAGMENT,
        defines: { PRIM: prim, LIGHT: light, DATA: data ? 1 : 0, STYLE: style },
        uniforms: {
            u_light: { value: new THREE.Vector4(L.ka, L.kd, L.ks, L.shine) },
            u_ortho: { value: 1 },
            u_nlev: { value: opts.levels | 0 },
            u_lw: { value: opts.lineWidth },
            u_vp: { value: new THREE.Vector2(1, 1) },
            u_cmap_n: { value: opts.cmapN || 1024 },
            u_color: { value: new THREE.Vector4(...opts.color) },
            u_nan_color: { value: new THREE.Vector4(...opts.nan) },
            u_contour_color: { value: new THREE.Vector4(...opts.contour) },
            u_cmap: { value: opts.cmap || null },
        },
        side: THREE.DoubleSide,
        depthFunc: THREE.LessDepth,
        blending: THREE.NoBlending,
    });
    // Translucent: premultiplied colours over the framebuffer (ONE, ONE_MINUS_SRC_ALPHA), as render.
    mat.blendSrc = THREE.OneFactor;
    mat.blendDst = THREE.OneMinusSrcAlphaFactor;
    mat.blendEquation = THREE.AddEquation;
    mat.blendSrcAlpha = THREE.OneFactor;
    mat.blendDstAlpha = THREE.OneMinusSrcAlphaFactor;
    mat.blendEquationAlpha = THREE.AddEquation;
    mat.forceSinglePass = false; // a translucent double-sided surface: far side first, then near side
    return mat;
}

// Opacity a: opaque (written depth, no blending) or translucent (drawn after the opaque surfaces,
// far side then near side, blended, no depth written).
export function setOpacity(mat, a) {
    mat.uniforms.u_color.value.w = a;
    const trans = a < 1;
    mat.transparent = trans;
    mat.depthWrite = !trans;
    mat.blending = trans ? THREE.CustomBlending : THREE.NoBlending;
}

// The edges of a triangle list (each once) as quads for PRIM 2: four corners per edge, each with its
// end's position, the other end's, the corner code and the node whose t it carries (`nodeOf`; the
// t attribute is gathered from the nodes' t per frame).
export function wireGeometry(points, indices) {
    const seen = new Set(), ends = [];
    for (let i = 0; i < indices.length; i += 3)
        for (let k = 0; k < 3; k++) {
            let a = indices[i + k], b = indices[i + (k + 1) % 3];
            if (a > b) [a, b] = [b, a];
            const key = a * 4294967296 + b;
            if (!seen.has(key)) {
                seen.add(key);
                ends.push(a, b);
            }
        }
    const E = ends.length / 2;
    const pos = new Float32Array(12 * E), oth = new Float32Array(12 * E), corner = new Float32Array(8 * E);
    const nodeOf = new Uint32Array(4 * E), idx = new Uint32Array(6 * E);
    const CORNERS = [[-1, 1], [-1, -1], [1, 1], [1, -1]]; // GS_LINES's strip: first end +, -, second end +, -
    for (let e = 0; e < E; e++) {
        const a = ends[2 * e], b = ends[2 * e + 1];
        for (let c = 0; c < 4; c++) {
            const v = 4 * e + c, self = c < 2 ? a : b, other = c < 2 ? b : a;
            for (let k = 0; k < 3; k++) {
                pos[3 * v + k] = points[3 * self + k];
                oth[3 * v + k] = points[3 * other + k];
            }
            corner[2 * v] = CORNERS[c][0];
            corner[2 * v + 1] = CORNERS[c][1];
            nodeOf[v] = self;
        }
        idx.set([4 * e, 4 * e + 1, 4 * e + 2, 4 * e + 2, 4 * e + 1, 4 * e + 3], 6 * e);
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('other', new THREE.BufferAttribute(oth, 3));
    geo.setAttribute('corner', new THREE.BufferAttribute(corner, 2));
    const t = new THREE.BufferAttribute(new Float32Array(4 * E), 1);
    t.setUsage(THREE.DynamicDrawUsage);
    geo.setAttribute('t', t);
    geo.setIndex(new THREE.BufferAttribute(idx, 1));
    return { geometry: geo, t, nodeOf };
}
