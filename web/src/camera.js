// The camera: thorax's own model (include/thorax/render/render.h, src/render/camera.c), so that the
// page starts at exactly `thorax render`'s picture. A camera is {eye, center, up, height, fov_deg}
// in model coordinates (mm); fov_deg 0 is orthographic with `height` the visible height.
// Eye space is OpenGL's: the eye at the origin looking along -z, +y up, +x to the image's right.
// Matrices are 4 x 4, column-major (m[col * 4 + row]), in double (plain arrays).

export const VIEW_NAMES = ['anterior', 'posterior', 'left', 'right', 'superior', 'inferior'];

// Direction from the centre toward the eye, and the image's up, per view (camera.c view_axes).
const VIEW_BACK = [[0, 1, 0], [0, -1, 0], [-1, 0, 0], [1, 0, 0], [0, 0, 1], [0, 0, -1]];
const VIEW_UP = [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 1, 0], [0, 1, 0]];

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => Math.sqrt(dot(a, a));

export function copyCamera(c) {
    return { eye: c.eye.slice(), center: c.center.slice(), up: c.up.slice(), height: c.height, fov_deg: c.fov_deg || 0 };
}

// thx_camera_view: the standard view `name` framing the box lo..hi in a viewport of aspect w / h.
export function viewCamera(name, lo, hi, aspect) {
    let v = VIEW_NAMES.indexOf(name);
    if (v < 0) v = 0;
    const back = VIEW_BACK[v], up = VIEW_UP[v];
    const right = cross(up, back);
    const c = [0, 0, 0], ext = [0, 0, 0];
    let diag = 0;
    for (let k = 0; k < 3; k++) {
        c[k] = 0.5 * (lo[k] + hi[k]);
        ext[k] = Math.abs(hi[k] - lo[k]);
        diag += ext[k] * ext[k];
    }
    diag = Math.sqrt(diag);
    // Axis-aligned frame: the extent across the image is the box's size along that axis.
    const eh = Math.abs(right[0]) * ext[0] + Math.abs(right[1]) * ext[1] + Math.abs(right[2]) * ext[2];
    const ev = Math.abs(up[0]) * ext[0] + Math.abs(up[1]) * ext[1] + Math.abs(up[2]) * ext[2];
    if (!(aspect > 0) || !Number.isFinite(aspect)) aspect = 1;
    let height = Math.max(ev, eh / aspect) * 1.1; // a 5% margin on each side
    if (!(height > 0) || !Number.isFinite(height)) height = 1;
    const dist = 2 * diag + height;
    return {
        eye: [c[0] + dist * back[0], c[1] + dist * back[1], c[2] + dist * back[2]],
        center: c,
        up: up.slice(),
        height,
        fov_deg: 0,
    };
}

// A standard view as the page gives it (META.views[name]: eye, center, up and the extents eh, ev
// across and up the image) at aspect w / h: thx_camera_view's height rule.
export function cameraFromView(v, aspect) {
    if (!(aspect > 0) || !Number.isFinite(aspect)) aspect = 1;
    const [eh, ev] = v.extent;
    let height = Math.max(ev, eh / aspect) * 1.1; // a 5% margin on each side
    if (!(height > 0) || !Number.isFinite(height)) height = 1;
    return { eye: v.eye.slice(), center: v.center.slice(), up: v.up.slice(), height, fov_deg: 0 };
}

// cam_frame: the camera's orthonormal right, up and back (centre toward eye); null if degenerate.
export function cameraFrame(cam) {
    const b = sub(cam.eye, cam.center);
    const lb = norm(b);
    if (!(lb > 0) || !Number.isFinite(lb)) return null;
    for (let k = 0; k < 3; k++) b[k] /= lb;
    const r = cross(cam.up, b);
    const lr = norm(r), lu = norm(cam.up);
    if (!(lr > 1e-9 * lu) || !Number.isFinite(lr)) return null;
    for (let k = 0; k < 3; k++) r[k] /= lr;
    const u = cross(b, r); // up = back x right, unit
    return { right: r, up: u, back: b };
}

// cam_view_matrix: model to eye space.
export function viewMatrix(cam) {
    const m = new Array(16).fill(0);
    const f = cameraFrame(cam);
    if (!f) {
        m[0] = m[5] = m[10] = m[15] = 1;
        return m;
    }
    for (let k = 0; k < 3; k++) {
        m[k * 4 + 0] = f.right[k];
        m[k * 4 + 1] = f.up[k];
        m[k * 4 + 2] = f.back[k];
    }
    m[12] = -dot(f.right, cam.eye);
    m[13] = -dot(f.up, cam.eye);
    m[14] = -dot(f.back, cam.eye);
    m[15] = 1;
    return m;
}

// cam_proj_matrix: the projection for aspect w / h between the depths znear < zfar.
export function projMatrix(cam, aspect, znear, zfar) {
    const m = new Array(16).fill(0);
    const fn = zfar - znear;
    if (cam.fov_deg > 0) {
        const f = 1 / Math.tan(0.5 * cam.fov_deg * Math.PI / 180);
        m[0] = f / aspect;
        m[5] = f;
        m[10] = -(zfar + znear) / fn;
        m[11] = -1;
        m[14] = -2 * zfar * znear / fn;
    } else {
        const hh = 0.5 * cam.height, hw = hh * aspect;
        m[0] = 1 / hw;
        m[5] = 1 / hh;
        m[10] = -2 / fn;
        m[14] = -(zfar + znear) / fn;
        m[15] = 1;
    }
    return m;
}

// cam_depth_range: depths in front of the eye that enclose the box lo..hi with a margin.
export function depthRange(cam, lo, hi) {
    const f = cameraFrame(cam);
    if (!f) return [1, 2];
    let dmin = Infinity, dmax = -Infinity, size = 0;
    for (let i = 0; i < 8; i++) {
        const p = [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]];
        const d = -dot(sub(p, cam.eye), f.back);
        dmin = Math.min(dmin, d);
        dmax = Math.max(dmax, d);
    }
    for (let k = 0; k < 3; k++) size += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    if (!Number.isFinite(dmin) || !Number.isFinite(dmax)) return [1, 2];
    const margin = 0.02 * (dmax - dmin) + 1e-3 * Math.sqrt(size) + 1e-6 * (Math.abs(dmax) + 1);
    let zn = dmin - margin, zf = dmax + margin;
    if (cam.fov_deg > 0) {
        if (zf <= 0) zf = 1;
        if (zn < zf / 2000) zn = zf / 2000;
    }
    return [zn, zf];
}

// thx_camera_ray: the ray through CSS pixel (x, y) of a w x h view (y down from the top).
export function cameraRay(cam, w, h, x, y) {
    const f = cameraFrame(cam);
    if (!f || w <= 0 || h <= 0) return null;
    const aspect = w / h, nx = 2 * x / w - 1, ny = 1 - 2 * y / h;
    const origin = [0, 0, 0], dir = [0, 0, 0];
    if (cam.fov_deg > 0) {
        const ty = Math.tan(0.5 * cam.fov_deg * Math.PI / 180), tx = ty * aspect;
        for (let k = 0; k < 3; k++) {
            origin[k] = cam.eye[k];
            dir[k] = -f.back[k] + nx * tx * f.right[k] + ny * ty * f.up[k];
        }
        const n = norm(dir);
        for (let k = 0; k < 3; k++) dir[k] /= n;
    } else {
        const hh = 0.5 * cam.height, hw = hh * aspect;
        if (!(hh > 0)) return null;
        for (let k = 0; k < 3; k++) {
            origin[k] = cam.eye[k] + nx * hw * f.right[k] + ny * hh * f.up[k];
            dir[k] = -f.back[k];
        }
    }
    return { origin, dir };
}

// thx_camera_project: CSS pixel position (x right, y down) and depth of the point p, or null.
export function projectPoint(cam, w, h, p) {
    const f = cameraFrame(cam);
    if (!f || w <= 0 || h <= 0) return null;
    const q = sub(p, cam.eye);
    const xe = dot(q, f.right), ye = dot(q, f.up), d = -dot(q, f.back);
    const aspect = w / h;
    let nx, ny;
    if (cam.fov_deg > 0) {
        if (!(d > 0)) return null;
        const s = 1 / Math.tan(0.5 * cam.fov_deg * Math.PI / 180);
        nx = s / aspect * xe / d;
        ny = s * ye / d;
    } else {
        const hh = 0.5 * cam.height, hw = hh * aspect;
        if (!(hh > 0)) return null;
        nx = xe / hw;
        ny = ye / hh;
    }
    return { x: 0.5 * (nx + 1) * w, y: 0.5 * (1 - ny) * h, depth: d };
}

// Rodrigues: v rotated by angle a about the unit axis k.
function rotate(v, k, a) {
    const c = Math.cos(a), s = Math.sin(a), kv = cross(k, v), kd = dot(k, v) * (1 - c);
    return [v[0] * c + kv[0] * s + k[0] * kd, v[1] * c + kv[1] * s + k[1] * kd, v[2] * c + kv[2] * s + k[2] * kd];
}

// A drag of (dx, dy) CSS pixels in a view `size` pixels high turns the model about the centre as a
// trackball would (the point under the cursor follows it); the camera turns the other way.
export function orbit(cam, dx, dy, size) {
    const f = cameraFrame(cam);
    const len = Math.hypot(dx, dy);
    if (!f || !(len > 0)) return cam;
    // The model's rotation axis in eye space is z x (dx, -dy, 0) = (dy, dx, 0); in model space:
    const axis = [0, 1, 2].map((k) => dy * f.right[k] + dx * f.up[k]);
    const la = norm(axis);
    for (let k = 0; k < 3; k++) axis[k] /= la;
    const angle = -Math.PI * len / Math.max(size, 1);
    const back = rotate(sub(cam.eye, cam.center), axis, angle);
    const up = rotate(f.up, axis, angle);
    const out = copyCamera(cam);
    for (let k = 0; k < 3; k++) out.eye[k] = cam.center[k] + back[k];
    out.up = up;
    return out;
}

// Zoom by a factor (> 1 shows more): the orthographic height, or the eye's distance in perspective.
export function zoom(cam, factor) {
    const out = copyCamera(cam);
    if (cam.fov_deg > 0) {
        for (let k = 0; k < 3; k++) out.eye[k] = cam.center[k] + factor * (cam.eye[k] - cam.center[k]);
    } else {
        out.height = cam.height * factor;
    }
    return out;
}

// thx_picture_orientation_text: the anatomical letters of the left, right, top and bottom edges.
// ax, sg: canonical axis k (0 the subject's right, 1 anterior, 2 cranial) is sg[k] times model
// axis ax[k].
export function orientationLetters(cam, ax, sg) {
    const f0 = sub(cam.center, cam.eye);
    const lf = norm(f0);
    if (!(lf > 0)) return ['', '', '', ''];
    const f = f0.map((x) => x / lf);
    const r0 = cross(f, cam.up); // the renderer's look-at: right = forward x up, up = right x forward
    const lr = norm(r0);
    if (!(lr > 0) || !Number.isFinite(lr)) return ['', '', '', ''];
    const r = r0.map((x) => x / lr);
    const u = cross(r, f);
    const POS = 'RAS', NEG = 'LPI';
    const lettersOf = (e) => {
        const c = [0, 1, 2].map((k) => sg[k] * e[ax[k]]);
        const order = [0, 1, 2];
        for (let i = 0; i < 3; i++)
            for (let j = i + 1; j < 3; j++)
                if (Math.abs(c[order[j]]) > Math.abs(c[order[i]]) + 1e-12) {
                    const t = order[i];
                    order[i] = order[j];
                    order[j] = t;
                }
        let text = '';
        for (let i = 0; i < 3; i++) {
            const k = order[i];
            if (i > 0 && Math.abs(c[k]) < 0.35) break; // only axes within about 70 degrees
            text += c[k] >= 0 ? POS[k] : NEG[k];
        }
        return text;
    };
    return [lettersOf(r.map((x) => -x)), lettersOf(r), lettersOf(u), lettersOf(u.map((x) => -x))];
}
