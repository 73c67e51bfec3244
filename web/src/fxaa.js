// render's FXAA (src/render/render_readback.c, fxaa: after Lottes' FXAA 3.11 "quality") on the GPU:
// when the page draws with one sample (a software rasterizer, render's rule), the scene is drawn into
// an offscreen target and smoothed into the canvas exactly as render smooths its single-sampled
// picture on the CPU, so that edges (silhouettes, contour lines, wire edges) match render's pixels.
// The arithmetic is render's, step for step, on the same 8-bit premultiplied pixels, in GL's row
// order (y up), clamped at the borders. One full-screen pass: a software rasterizer runs it for every
// pixel (measured in Chromium's SwiftShader on 480 x 540: about 20 ms; splitting off render's early
// exit into a first pass with the stencil or depth test rejecting its pixels in a second was slower,
// the rasterizer shades before it tests), so the page smooths the pictures it keeps, not every frame
// step (scene.js, render).
import * as THREE from 'three';

const VERTEX = /* glsl */ `
precision highp float;
in vec3 position;
void main() {
    gl_Position = vec4(position.xy, 0.0, 1.0);
}
`;

const COMMON = /* glsl */ `
precision highp float;
precision highp int;
uniform sampler2D u_src; // the scene: premultiplied RGBA, 8 bits
uniform ivec2 u_size;
out vec4 o_color;

vec4 bytes(ivec2 p) {
    return floor(texelFetch(u_src, clamp(p, ivec2(0), u_size - 1), 0) * 255.0 + 0.5);
}
// render's luma: alpha counts, so that edges against a transparent background are smoothed too.
float L(ivec2 p) {
    vec4 c = bytes(p);
    return (0.299 * c.r + 0.587 * c.g + 0.114 * c.b + 0.5 * (255.0 - c.a)) * (1.0 / 255.0);
}

`;

// Each pixel: kept when its luma contrast with its four neighbours is small, else blended with its
// neighbour across the edge by how near it is to the edge's nearer end.
const SMOOTH = /* glsl */ `${COMMON}
const int STEPS[10] = int[10](1, 1, 1, 1, 1, 2, 2, 2, 4, 8);

void main() {
    ivec2 q = ivec2(gl_FragCoord.xy);
    float lm = L(q), ln = L(q + ivec2(0, 1)), ls = L(q - ivec2(0, 1)), le = L(q + ivec2(1, 0)), lw = L(q - ivec2(1, 0));
    float lmax = max(lm, max(max(ln, ls), max(le, lw)));
    float lmin = min(lm, min(min(ln, ls), min(le, lw)));
    float range = lmax - lmin;
    vec4 a = bytes(q);
    if (range < max(0.0312, 0.125 * lmax)) {
        o_color = a / 255.0;
        return;
    }
    float lne = L(q + ivec2(1, 1)), lnw = L(q + ivec2(-1, 1)), lse = L(q + ivec2(1, -1)), lsw = L(q + ivec2(-1, -1));
    float avg = (2.0 * (ln + ls + le + lw) + lne + lnw + lse + lsw) / 12.0;
    float sub = min(abs(avg - lm) / range, 1.0);
    sub = sub * sub * (3.0 - 2.0 * sub);
    sub = 0.75 * sub * sub;
    float eh = abs(lsw + lnw - 2.0 * lw) + 2.0 * abs(ls + ln - 2.0 * lm) + abs(lse + lne - 2.0 * le);
    float ev = abs(lnw + lne - 2.0 * ln) + 2.0 * abs(lw + le - 2.0 * lm) + abs(lsw + lse - 2.0 * ls);
    bool horz = eh >= ev; // the edge runs along x; its sides differ along y
    float l1 = horz ? ls : lw, l2 = horz ? ln : le;
    float g1 = abs(l1 - lm), g2 = abs(l2 - lm);
    int step = g1 >= g2 ? -1 : 1; // toward the side of the steeper gradient
    float grad = 0.25 * max(g1, g2);
    float llocal = 0.5 * ((step < 0 ? l1 : l2) + lm);
    ivec2 along = horz ? ivec2(1, 0) : ivec2(0, 1), across = horz ? ivec2(0, step) : ivec2(step, 0);
    // the luma on the edge (between this row and the next across it), k pixels along
#define EDGE(k) (0.5 * (L(q + (k) * along) + L(q + (k) * along + across)))
    int k1 = -1, k2 = 1;
    float d1 = EDGE(k1) - llocal, d2 = EDGE(k2) - llocal;
    bool r1 = abs(d1) >= grad, r2 = abs(d2) >= grad;
    for (int s = 0; s < 10; s++) {
        if (r1 && r2) break;
        if (!r1) {
            k1 -= STEPS[s];
            d1 = EDGE(k1) - llocal;
            r1 = abs(d1) >= grad;
        }
        if (!r2) {
            k2 += STEPS[s];
            d2 = EDGE(k2) - llocal;
            r2 = abs(d2) >= grad;
        }
    }
    float dist1 = float(-k1), dist2 = float(k2);
    bool first = dist1 < dist2;
    float off = 0.5 - min(dist1, dist2) / (dist1 + dist2);
    bool good = ((first ? d1 : d2) < 0.0) != (lm < llocal);
    off = max(good ? off : 0.0, sub);
    vec4 b = bytes(q + across);
    o_color = floor(a + off * (b - a) + 0.5) / 255.0;
}
`;

export class Fxaa {
    constructor(renderer) {
        this.renderer = renderer;
        this.target = new THREE.WebGLRenderTarget(1, 1, {
            type: THREE.UnsignedByteType,
            format: THREE.RGBAFormat,
            minFilter: THREE.NearestFilter,
            magFilter: THREE.NearestFilter,
            generateMipmaps: false,
            depthBuffer: true,
            stencilBuffer: false,
            samples: 0,
        });
        this.target.texture.colorSpace = THREE.NoColorSpace;
        this.size = new THREE.Vector2(1, 1);
        this.material = new THREE.RawShaderMaterial({
            glslVersion: THREE.GLSL3,
            vertexShader: VERTEX,
            fragmentShader: SMOOTH,
            uniforms: { u_src: { value: this.target.texture }, u_size: { value: this.size } },
            depthTest: false,
            depthWrite: false,
            blending: THREE.NoBlending,
        });
        // One triangle over the whole view.
        const geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
        const tri = new THREE.Mesh(geo, this.material);
        tri.frustumCulled = false;
        this.scene = new THREE.Scene();
        this.scene.add(tri);
        this.camera = new THREE.Camera();
    }

    // The drawing buffer's size in pixels.
    setSize(w, h) {
        this.target.setSize(w, h);
        this.size.set(w, h);
    }

    // The scene into the target, then smoothed into the canvas.
    render(scene, camera) {
        const r = this.renderer;
        r.setRenderTarget(this.target);
        r.render(scene, camera);
        r.setRenderTarget(null);
        r.render(this.scene, this.camera);
    }
}
