// The 3D view: three.js's WebGL2 renderer drawing the surfaces with render's shader (shader.js)
// under render's camera (camera.js), the layers (surfaces with `layer`: one frame's values, whatever
// the frame shown), the scan's planes (planes.js), the electrodes and the picked node's mark,
// picking (the model's surfaces only), and the canvas's pixels for the tests.
import * as THREE from 'three';
import { viewMatrix, projMatrix, depthRange, cameraRay, cameraFrame } from './camera.js';
import { surfaceMaterial, setOpacity, colormapTexture, styleCode, wireGeometry } from './shader.js';
import { makePlanes } from './planes.js';
import { Fxaa } from './fxaa.js';

// No colour management anywhere: the colour map's bytes go to the framebuffer as they are, as in
// render (which has no sRGB conversion).
THREE.ColorManagement.enabled = false;

const LIGHT_OF_MODE = { flat: 1, gouraud: 2, phong: 3 };
const MARK_COLOR = [1.0, 0.85, 0.0, 1]; // the picked node
const ELECTRODE_COLOR = [0x10 / 255, 0xa0 / 255, 0x40 / 255, 1]; // render's (--electrodes, src/picture/picture_data.c)

// Whether the triangles close a surface consistently oriented (each edge used twice, once each
// way): +1 facing outward (counter-clockwise seen from outside), -1 inward, 0 not closed. render
// draws such an opaque surface, seen from outside, without the side that cannot be seen.
function closedOrientation(points, idx, N) {
    const T = idx.length / 3;
    if (!T) return 0;
    const keys = new Float64Array(3 * T); // (min, max) as one number, times 2, plus 1 when a > b
    for (let i = 0; i < 3 * T; i++) {
        const a = idx[i], b = idx[i - (i % 3) + ((i % 3) + 1) % 3];
        keys[i] = a < b ? 2 * (a * N + b) : 2 * (b * N + a) + 1;
    }
    keys.sort();
    for (let i = 0; i < keys.length; i += 2) if (keys[i] % 2 !== 0 || keys[i + 1] !== keys[i] + 1) return 0;
    let vol = 0; // six times the signed volume
    for (let i = 0; i < 3 * T; i += 3) {
        const a = 3 * idx[i], b = 3 * idx[i + 1], c = 3 * idx[i + 2];
        const ax = points[a], ay = points[a + 1], az = points[a + 2], bx = points[b], by = points[b + 1], bz = points[b + 2];
        const cx = points[c], cy = points[c + 1], cz = points[c + 2];
        vol += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
    }
    return vol > 0 ? 1 : vol < 0 ? -1 : 0;
}

// The GL's renderer string, and whether it rasterizes on the CPU (SwiftShader, llvmpipe, ...).
function rendererName(gl) {
    let name = String(gl.getParameter(gl.RENDERER) || '');
    if (/^WebKit WebGL$/i.test(name)) { // Chromium masks it; its debug extension tells
        const ext = gl.getExtension('WEBGL_debug_renderer_info');
        if (ext) name = String(gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) || name);
    }
    return name;
}
const SOFTWARE = /swiftshader|llvmpipe|softpipe|software rasterizer|basic render driver/i;

function makeRenderer(canvas, antialias) {
    return new THREE.WebGLRenderer({
        canvas,
        antialias,
        alpha: true,
        premultipliedAlpha: true,
        preserveDrawingBuffer: true, // the tests read the pixels back
    });
}

export class View3D {
    // canvas: the WebGL canvas (replaced by a new one when multisampled: see this.canvas); meta,
    // blobs: the page's data; series: per surface, its Series or null.
    constructor(canvas, meta, blobs, series) {
        this.meta = meta;
        // Multisampled on a GPU; one sample on a software rasterizer, where multisampling costs two
        // to three times the frame (render's rule too: docs/decisions.md, "Renderer"). The context
        // is made without first, and remade with on a new canvas when the GL is not software.
        this.renderer = makeRenderer(canvas, false);
        let gl = this.renderer.getContext();
        this.contextMs = performance.now(); // the page's timings: the WebGL context made
        if (!(typeof WebGL2RenderingContext !== 'undefined' && gl instanceof WebGL2RenderingContext))
            throw new Error('WebGL 2 is not available in this browser');
        this.glRenderer = rendererName(gl);
        this.multisampled = !SOFTWARE.test(this.glRenderer);
        if (this.multisampled) {
            this.renderer.dispose();
            const fresh = canvas.cloneNode(false);
            canvas.replaceWith(fresh);
            canvas = fresh;
            this.renderer = makeRenderer(canvas, true);
            gl = this.renderer.getContext();
        }
        this.canvas = canvas;
        this.gl = gl;
        // One sample: smoothed as render smooths its single-sampled picture (FXAA, fxaa.js).
        this.fxaa = this.multisampled ? null : new Fxaa(this.renderer);
        this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
        this.renderer.toneMapping = THREE.NoToneMapping;
        this.renderer.sortObjects = true;
        const bg = meta.background || [1, 1, 1, 1];
        this.renderer.setClearColor(new THREE.Color(bg[0], bg[1], bg[2]), bg[3]); // premultiplied by three

        this.scene = new THREE.Scene();
        this.scene.matrixWorldAutoUpdate = true;
        // A bare camera whose matrices are ours (render's), never recomputed by three.js.
        this.camera = new THREE.Camera();
        this.camera.matrixAutoUpdate = false;
        this.camera.matrixWorldAutoUpdate = false;
        this.cam = null;
        this.width = 1;
        this.height = 1;
        this.dpr = 1;

        const nanColor = meta.nan_color || [0.7, 0.45, 0.7, 1];
        const style = meta.style || { kind: 'continuous', levels: 10, contour_color: [0, 0, 0, 1], line_width: 1.5 };
        const light = meta.light || { ka: 0.25, kd: 0.75, ks: 0.2, shine: 40 };
        this.light = light;
        this.lineWidth = style.line_width > 0 ? style.line_width : 1.5; // contour lines (render's default)
        this.textures = (meta.colormaps || []).map((c) => colormapTexture(blobs[c.blob], c.n));

        // The surfaces.
        this.surfaces = [];
        const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
        meta.surfaces.forEach((s, index) => {
            const pts = blobs[s.points], idx = blobs[s.indices], nrm = blobs[s.normals];
            if (pts.length !== 3 * s.nodes || idx.length !== 3 * s.triangles || nrm.length !== 3 * s.nodes)
                throw new Error(`surface "${s.name}": its blobs do not hold ${s.nodes} nodes and ${s.triangles} triangles`);
            for (let i = 0; i < idx.length; i++)
                if (idx[i] >= s.nodes) throw new Error(`surface "${s.name}": triangle corner ${idx[i]} is not a node`);
            const geo = new THREE.BufferGeometry();
            geo.setAttribute('position', new THREE.BufferAttribute(pts, 3));
            geo.setAttribute('normal', new THREE.BufferAttribute(nrm, 3));
            const tArr = new Float32Array(s.nodes);
            const tAttr = new THREE.BufferAttribute(tArr, 1);
            tAttr.setUsage(THREE.DynamicDrawUsage);
            geo.setAttribute('t', tAttr);
            geo.setIndex(new THREE.BufferAttribute(idx, 1));
            geo.computeBoundingSphere();
            geo.computeBoundingBox();
            const box = { lo: geo.boundingBox.min.toArray(), hi: geo.boundingBox.max.toArray() };
            if (s.mode !== 'hidden' && s.nodes > 0)
                for (let k = 0; k < 3; k++) {
                    lo[k] = Math.min(lo[k], box.lo[k]);
                    hi[k] = Math.max(hi[k], box.hi[k]);
                }

            const hasData = !!series[index] && s.mode !== 'hidden';
            const prim = s.mode === 'wire' ? 2 : 0;
            // render's widths in pixels: the surface's own (line_width), else 1 for wire edges and
            // style.line_width for contour lines.
            const lineWidth = s.line_width > 0 ? s.line_width : prim === 2 ? 1 : this.lineWidth;
            const lightMode = prim === 2 ? 0 : LIGHT_OF_MODE[s.mode] || 2;
            const color = (s.color || [0.85, 0.85, 0.85, 1]).slice(0, 3);
            const opacity = s.opacity !== undefined ? s.opacity : s.color ? s.color[3] : 1;
            // The data's style: the surface's own (data.style) when the page gives one, else META's.
            const own = (s.data && s.data.style) || {};
            const kind = own.kind || style.kind, levels = own.levels || style.levels || 1;
            const mat = surfaceMaterial(prim, lightMode, hasData, hasData ? styleCode(kind) : 0, {
                color: [...color, opacity],
                nan: nanColor,
                contour: style.contour_color || [0, 0, 0, 1],
                light,
                levels,
                lineWidth,
                cmap: hasData ? this.textures[s.data.colormap] : null,
                cmapN: hasData ? meta.colormaps[s.data.colormap].n : 1024,
            });
            setOpacity(mat, opacity);
            // The triangles: drawn (unless wire or hidden) and picked.
            const mesh = new THREE.Mesh(geo, mat);
            mesh.frustumCulled = false;
            mesh.matrixAutoUpdate = false;
            let drawn = mesh, wire = null;
            if (prim === 2) {
                wire = wireGeometry(pts, idx);
                drawn = new THREE.Mesh(wire.geometry, mat);
                drawn.frustumCulled = false;
                drawn.matrixAutoUpdate = false;
            }
            if (s.mode !== 'hidden') this.scene.add(drawn);
            const surf = {
                index,
                name: s.name,
                role: s.role,
                meta: s,
                layer: !!s.layer, // drawn with its one frame's values, never picked
                lineWidth,
                mesh,
                drawn,
                material: mat,
                tAttr,
                tArr,
                wire,
                closed: prim === 0 ? closedOrientation(pts, idx, s.nodes) : 0,
                series: series[index],
                box,
                visible: s.visible !== false && s.mode !== 'hidden',
                opacity,
            };
            this.surfaces.push(surf);
            this.applyVisibility(surf);
            if (surf.layer && surf.series) this.fillSurface(surf, 0); // its one frame, once
        });

        // The scan's planes, in the box as render counts them.
        this.planes = makePlanes(meta.planes, blobs);
        for (const p of this.planes) {
            this.scene.add(p.mesh);
            for (const c of p.corners)
                for (let k = 0; k < 3; k++) {
                    lo[k] = Math.min(lo[k], c[k]);
                    hi[k] = Math.max(hi[k], c[k]);
                }
        }

        // The electrodes: spheres 1.2% of the box's diagonal across (at least 2 mm), as render's.
        const vb = meta.view && meta.view.box;
        for (let k = 0; k < 3; k++) {
            if (!(lo[k] <= hi[k]) && vb) {
                lo[k] = vb.lo[k];
                hi[k] = vb.hi[k];
            }
        }
        this.box = { lo, hi };
        const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
        this.diag = diag;
        const opts = (color) => ({ color, nan: nanColor, contour: [0, 0, 0, 1], light, levels: 1, lineWidth: 1 });
        this.electrodes = new THREE.Group();
        const eGeo = new THREE.SphereGeometry(Math.max(2, 0.006 * diag), 16, 12);
        const eMat = surfaceMaterial(0, 3, false, 0, opts(ELECTRODE_COLOR));
        for (const e of meta.electrodes || []) {
            const m = new THREE.Mesh(eGeo, eMat);
            m.position.set(e.position[0], e.position[1], e.position[2]);
            m.updateMatrix();
            m.matrixAutoUpdate = false;
            m.frustumCulled = false;
            this.electrodes.add(m);
            for (let k = 0; k < 3; k++) {
                this.box.lo[k] = Math.min(this.box.lo[k], e.position[k]);
                this.box.hi[k] = Math.max(this.box.hi[k], e.position[k]);
            }
        }
        this.scene.add(this.electrodes);
        // The picked node's mark.
        this.mark = new THREE.Mesh(new THREE.SphereGeometry(0.011 * diag, 20, 14), surfaceMaterial(0, 3, false, 0, opts(MARK_COLOR)));
        this.mark.visible = false;
        this.mark.frustumCulled = false;
        this.scene.add(this.mark);
        this.markSurface = -1;
        this.raycaster = new THREE.Raycaster();
        this.frame = -1;
    }

    applyVisibility(s) {
        const shown = s.visible && s.meta.mode !== 'hidden' && s.opacity > 0;
        s.drawn.visible = shown;
        setOpacity(s.material, s.opacity);
        // render: a closed, consistently oriented opaque surface seen from outside is drawn without
        // its far side (the same picture, half the triangles); translucent ones far side then near.
        const cull = s.opacity >= 1 && s.closed !== 0 && this.outside(s);
        s.material.side = !cull ? THREE.DoubleSide : s.closed > 0 ? THREE.FrontSide : THREE.BackSide;
    }

    // render's box_in_front: the surface's box lies beyond the near plane (always when orthographic).
    outside(s) {
        const cam = this.cam;
        if (!cam || !(cam.fov_deg > 0)) return true;
        const f = cameraFrame(cam), zn = this.znear;
        for (let i = 0; i < 8; i++) {
            const p = [i & 1 ? s.box.hi[0] : s.box.lo[0], i & 2 ? s.box.hi[1] : s.box.lo[1], i & 4 ? s.box.hi[2] : s.box.lo[2]];
            const d = -((p[0] - cam.eye[0]) * f.back[0] + (p[1] - cam.eye[1]) * f.back[1] + (p[2] - cam.eye[2]) * f.back[2]);
            if (!(d > zn)) return false;
        }
        return true;
    }

    setSurface(i, { visible, opacity }) {
        const s = this.surfaces[i];
        if (visible !== undefined) s.visible = !!visible && s.meta.mode !== 'hidden';
        if (opacity !== undefined) s.opacity = Math.min(Math.max(Number(opacity), 0), 1);
        this.applyVisibility(s);
        this.sortTranslucent();
        this.mark.visible = this.markSurface >= 0 && this.surfaces[this.markSurface].drawn.visible;
    }

    setElectrodesVisible(v) {
        this.electrodes.visible = !!v;
    }

    // The canvas at w x h CSS pixels, drawn at devicePixelRatio.
    setSize(w, h, dpr) {
        this.width = Math.max(1, Math.round(w));
        this.height = Math.max(1, Math.round(h));
        this.dpr = dpr || 1;
        this.renderer.setPixelRatio(this.dpr);
        this.renderer.setSize(this.width, this.height, true);
        const gl = this.gl;
        if (this.fxaa) this.fxaa.setSize(gl.drawingBufferWidth, gl.drawingBufferHeight);
        for (const s of this.surfaces) {
            const u = s.material.uniforms;
            // Pixels of the framebuffer: the surface's line width (its contour lines', or its wire edges').
            u.u_lw.value = s.lineWidth * this.dpr;
            u.u_vp.value.set(gl.drawingBufferWidth, gl.drawingBufferHeight);
        }
        if (this.cam) this.setCamera(this.cam);
    }

    // render's matrices for the camera at the canvas's aspect, the depth range around everything.
    setCamera(cam) {
        this.cam = cam;
        const [zn, zf] = depthRange(cam, this.box.lo, this.box.hi);
        this.znear = zn;
        const v = viewMatrix(cam), p = projMatrix(cam, this.width / this.height, zn, zf);
        this.camera.matrixWorldInverse.fromArray(v);
        this.camera.matrixWorld.copy(this.camera.matrixWorldInverse).invert();
        this.camera.projectionMatrix.fromArray(p);
        this.camera.projectionMatrixInverse.copy(this.camera.projectionMatrix).invert();
        const ortho = cam.fov_deg > 0 ? 0 : 1;
        for (const s of this.surfaces) s.material.uniforms.u_ortho.value = ortho;
        this.mark.material.uniforms.u_ortho.value = ortho;
        this.electrodes.children.forEach((m) => (m.material.uniforms.u_ortho.value = ortho));
        if (cam.fov_deg > 0) for (const s of this.surfaces) this.applyVisibility(s);
        this.sortTranslucent();
    }

    // render's order of the translucent surfaces: far to near by their boxes' centres.
    sortTranslucent() {
        const f = this.cam && cameraFrame(this.cam);
        if (!f) return;
        const depth = (s) => {
            let d = 0;
            for (let k = 0; k < 3; k++) d -= (0.5 * (s.box.lo[k] + s.box.hi[k]) - this.cam.eye[k]) * f.back[k];
            return d;
        };
        const tr = this.surfaces.filter((s) => s.opacity < 1).sort((a, b) => depth(b) - depth(a) || a.index - b.index);
        for (const s of this.surfaces) s.drawn.renderOrder = 0; // the opaque ones before the planes
        tr.forEach((s, j) => (s.drawn.renderOrder = j));
    }

    // Frame f's t into every model surface with data: one float per node, no allocation. The
    // layers keep their one frame.
    setFrame(f) {
        this.frame = f;
        for (const s of this.surfaces) if (s.series && !s.layer) this.fillSurface(s, f);
    }

    // Frame f of surface s's series into its t attribute (and its wire quads').
    fillSurface(s, f) {
        s.series.fillT(f, s.tArr);
        s.tAttr.clearUpdateRanges();
        s.tAttr.addUpdateRange(0, s.tArr.length);
        s.tAttr.needsUpdate = true;
        if (s.wire) { // the edges' corners carry their nodes' t
            const wt = s.wire.t.array, nodeOf = s.wire.nodeOf, t = s.tArr;
            for (let j = 0; j < wt.length; j++) wt[j] = t[nodeOf[j]];
            s.wire.t.clearUpdateRanges();
            s.wire.t.addUpdateRange(0, wt.length);
            s.wire.t.needsUpdate = true;
        }
    }

    // The scan's planes shown or not.
    setPlanesVisible(v) {
        for (const p of this.planes) p.mesh.visible = !!v;
    }

    // Draws the scene: multisampled on a GPU; with one sample, smoothed by render's FXAA when
    // `smooth` (a picture kept: the tests', the one shown once the view is still), else as it is (a
    // frame step while playing, dragging or turning: FXAA would double a software rasterizer's frame).
    render(smooth = true) {
        if (this.fxaa && smooth) this.fxaa.render(this.scene, this.camera);
        else this.renderer.render(this.scene, this.camera);
        this.smoothed = !!this.fxaa && smooth;
    }

    // Waits for the GPU (a one-pixel read).
    finish() {
        const px = new Uint8Array(4);
        this.gl.readPixels(0, 0, 1, 1, this.gl.RGBA, this.gl.UNSIGNED_BYTE, px);
    }

    // The node under CSS pixel (x, y): the nearest corner of the first visible triangle of a model
    // surface hit (the largest barycentric weight). {surface index, node} or null. The layers and
    // the planes are not picked (a click goes through them to the model's surfaces behind): a
    // layer has one frame, the picked node's plot is a series over the frames.
    pick(x, y) {
        const ray = cameraRay(this.cam, this.width, this.height, x, y);
        if (!ray) return null;
        this.raycaster.ray.origin.set(...ray.origin);
        this.raycaster.ray.direction.set(...ray.dir);
        this.raycaster.near = 0;
        this.raycaster.far = Infinity;
        const objs = this.surfaces.filter((s) => s.drawn.visible && !s.layer).map((s) => s.mesh);
        const hits = this.raycaster.intersectObjects(objs, false);
        if (!hits.length) return null;
        const h = hits[0];
        const s = this.surfaces.find((q) => q.mesh === h.object);
        const tri = new THREE.Triangle();
        const pos = s.mesh.geometry.getAttribute('position');
        const a = h.face.a, b = h.face.b, c = h.face.c;
        tri.setFromAttributeAndIndices(pos, a, b, c);
        const w = new THREE.Vector3();
        tri.getBarycoord(h.point, w);
        const node = w.x >= w.y && w.x >= w.z ? a : w.y >= w.z ? b : c;
        return { surface: s.index, node };
    }

    // Marks node i of surface s (or nothing: s < 0).
    setMark(s, i) {
        this.markSurface = s;
        if (s < 0) {
            this.mark.visible = false;
            return;
        }
        const p = this.surfaces[s].mesh.geometry.getAttribute('position');
        this.mark.position.set(p.getX(i), p.getY(i), p.getZ(i));
        this.mark.visible = this.surfaces[s].drawn.visible;
    }

    // The canvas's RGBA (draw-buffer pixels, top row first), divided by alpha as render's PNG.
    pixels() {
        const gl = this.gl, w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
        const buf = new Uint8Array(4 * w * h), out = new Uint8Array(4 * w * h);
        gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, buf);
        const row = 4 * w;
        for (let y = 0; y < h; y++) {
            const src = (h - 1 - y) * row, dst = y * row;
            for (let x = 0; x < row; x += 4) {
                const a = buf[src + x + 3];
                for (let k = 0; k < 3; k++) {
                    const c = buf[src + x + k];
                    out[dst + x + k] = a === 255 || a === 0 ? c : Math.min(255, Math.round((c * 255) / a));
                }
                out[dst + x + 3] = a;
            }
        }
        return { width: w, height: h, data: out };
    }
}
