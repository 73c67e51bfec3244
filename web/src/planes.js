// The scan's planes (META.planes: render's --image, --image-plane): textured rectangles drawn as
// render draws them (src/render/render_shaders.c VS_PLANE and FS_PLANE, render_draw.c draw_plane):
// unlit, the texel's colour as it is, texels of alpha below 128 not drawn, linear filtering unless
// `nearest` (a label map); depth-tested and depth-written after the opaque surfaces and before the
// translucent ones, pushed back by a polygon offset (1, 1) so that lines lying in the plane (the
// scan's contour lines) stay in front of it.
import * as THREE from 'three';

const VERTEX = /* glsl */ `
precision highp float;
uniform mat4 modelViewMatrix, projectionMatrix;
in vec3 position;
in vec2 tc;
out vec2 v_tc;
void main() {
    v_tc = tc;
    gl_Position = projectionMatrix * (modelViewMatrix * vec4(position, 1.0));
}
`;

const FRAGMENT = /* glsl */ `
precision highp float;
uniform sampler2D u_tex;
in vec2 v_tc;
out vec4 o_color;
void main() {
    vec4 c = texture(u_tex, v_tc);
    if (c.a < 0.5) discard;
    o_color = vec4(c.rgb, 1.0);
}
`;

// Drawn after every opaque surface (three.js sorts its opaque list by renderOrder first).
export const PLANE_RENDER_ORDER = 1 << 20;

// The plane's four corners: origin, + u, + u + v, + v (render's triangle fan), texture coordinates
// (0, 0) to (1, 1): texel (a, b)'s centre at ((a + 0.5) / W, (b + 0.5) / H).
function planeGeometry(p) {
    const pos = new Float32Array(12), tc = new Float32Array(8);
    for (let c = 0; c < 4; c++) {
        const a = c === 1 || c === 2 ? 1 : 0, b = c >= 2 ? 1 : 0;
        for (let k = 0; k < 3; k++) pos[3 * c + k] = p.origin[k] + a * p.u[k] + b * p.v[k];
        tc[2 * c] = a;
        tc[2 * c + 1] = b;
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('tc', new THREE.BufferAttribute(tc, 2));
    geo.setIndex([0, 1, 2, 0, 2, 3]);
    return geo;
}

function planeTexture(texels, w, h, nearest) {
    const tex = new THREE.DataTexture(texels, w, h, THREE.RGBAFormat, THREE.UnsignedByteType);
    tex.colorSpace = THREE.NoColorSpace;
    const filter = nearest ? THREE.NearestFilter : THREE.LinearFilter;
    tex.magFilter = filter;
    tex.minFilter = filter;
    tex.wrapS = THREE.ClampToEdgeWrapping;
    tex.wrapT = THREE.ClampToEdgeWrapping;
    tex.generateMipmaps = false;
    tex.flipY = false; // row b = 0 of the texels at texture coordinate 0, as render uploads them
    tex.premultiplyAlpha = false;
    tex.unpackAlignment = 1;
    tex.needsUpdate = true;
    return tex;
}

// The planes as meshes (their corners are in `corners`, for the scene's box). Throws on a plane
// whose texels do not fit its size.
export function makePlanes(planes, blobs) {
    return (planes || []).map((p, k) => {
        const texels = blobs[p.texels];
        if (!(p.w > 0 && p.h > 0) || !texels || texels.length !== 4 * p.w * p.h)
            throw new Error(`scan plane ${k + 1}: its texels blob does not hold ${p.w} x ${p.h} RGBA texels`);
        const mat = new THREE.RawShaderMaterial({
            glslVersion: THREE.GLSL3,
            vertexShader: VERTEX,
            fragmentShader: FRAGMENT,
            uniforms: { u_tex: { value: planeTexture(texels, p.w, p.h, !!p.nearest) } },
            side: THREE.DoubleSide,
            depthFunc: THREE.LessDepth,
            depthTest: true,
            depthWrite: true,
            blending: THREE.NoBlending,
            polygonOffset: true,
            polygonOffsetFactor: 1,
            polygonOffsetUnits: 1,
        });
        const geo = planeGeometry(p);
        const mesh = new THREE.Mesh(geo, mat);
        mesh.frustumCulled = false;
        mesh.matrixAutoUpdate = false;
        mesh.renderOrder = PLANE_RENDER_ORDER;
        const pos = geo.getAttribute('position').array;
        const corners = [0, 1, 2, 3].map((c) => [pos[3 * c], pos[3 * c + 1], pos[3 * c + 2]]);
        return { mesh, corners };
    });
}
