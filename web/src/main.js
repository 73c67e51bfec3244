// The viewer's entry point (bundled into one IIFE by scripts/web.sh and embedded by
// `thorax export --format html`): reads the page's data, builds the page, and keeps the 3D view,
// the time bar and the plots at one frame. window.thorax holds the test hooks
// (docs/design/web.md, "The page's data, version 1").
import { readMeta, decodeBlobs, Series, leadSeries, PageError } from './data.js';
import { copyCamera, viewCamera, cameraFromView, orbit, zoom, orientationLetters, projectPoint, cameraFrame, VIEW_NAMES } from './camera.js';
import { View3D } from './scene.js';
import { LeadsPlot, NodePlot, drawColorBar } from './plots.js';
import { buildUI, buildMain, showError } from './ui.js';
import { fmtG, fmtTime } from './format.js';

const PLAY_FPS = 30; // frames of the series per second when playing
const DRAG_SLOP = 4; // CSS pixels a press may move and still be a click
const SETTLE_MS = 150; // a software rasterizer's picture is smoothed (FXAA) once still this long

let resolveReady, rejectReady;
const ready = new Promise((res, rej) => {
    resolveReady = res;
    rejectReady = rej;
});
ready.catch(() => {}); // the error is shown in the page; the tests see the rejection
let app = null;
const need = () => {
    if (!app) throw new Error('thorax: the page is not ready (await window.thorax.ready)');
    return app;
};

// The test hooks: window.thorax is set once the first picture is drawn (ready resolved), or once
// the page has failed (ready rejected with the message the page shows).
const hooks = {
    ready,
    meta: null,
    timings: { script_ms: null, load_ms: null, context_ms: null, scene_ms: null, first_picture_ms: null, shown_ms: null },
    setFrame: (f) => need().setFrame(f, true),
    frame: () => need().frame,
    setView: (name) => need().setView(name, true),
    setSize: (w, h) => need().setSize(w, h, true),
    setSurface: (name, opts) => need().setSurface(name, opts || {}, true),
    pickAt: (x, y) => need().pickAt(x, y),
    nodeSeries: (surface, node) => need().nodeSeries(surface, node),
    plotted: () => need().plotted(),
    marker: () => need().marker(),
    clickLeads: (x) => need().clickLeads(x),
    canvasPixels: () => need().canvasPixels(),
    benchFrames: (n) => need().benchFrames(n),
};

class App {
    constructor(ui, meta, blobs, series) {
        this.ui = ui;
        this.meta = meta;
        this.M = meta.frames;
        this.time = meta.time && meta.time.length === this.M ? meta.time : Array.from({ length: this.M }, (_, i) => i);
        this.series = series;
        this.leads = leadSeries(meta, blobs);
        this.cmapBytes = (meta.colormaps || []).map((c) => blobs[c.blob]);
        this.frame = 0;
        this.picked = null; // {surface, node, values}
        this.playing = false;
        this.userSized = false;
        this.viewName = this.initialView();
        this.standard = true; // the camera is a standard view (not turned or zoomed by hand)
        this.drawPending = false;
        this.view3d = new View3D(ui.canvas, meta, blobs, series);
        this.electrodesOn = true;
        this.nearestNormals = this.electrodeNormals(blobs);
        this.letterColor();
        this.wire();
        this.leadsPlot = this.leads && this.M > 0
            ? new LeadsPlot(ui.leadsCanvas, this.leads, this.time, meta.time_unit || '', meta.leads.unit || meta.unit || '', (f) => this.setFrame(f))
            : null;
        this.nodePlot = new NodePlot(ui.nodeCanvas, this.time, meta.time_unit || '', meta.unit || '', (f) => this.setFrame(f));
        this.bars = this.colorBars();
        this.renderPicked();
    }

    // The colour bars, one per distinct scale as render's (src/picture/picture.c collect_bars): the
    // surfaces with data (layers too) sharing colour map, quantity, unit, style and scale share a bar
    // titled with their names.
    colorBars() {
        const bars = [], byKey = new Map();
        this.meta.surfaces.forEach((s, i) => {
            const d = s.data, ser = this.series[i];
            if (!d || !ser || s.mode === 'hidden') return;
            const style = Object.assign({}, this.meta.style, d.style); // the surface's own style first
            const bands = style.kind === 'bands' || style.kind === 'bands+contours';
            const key = JSON.stringify([d.colormap, d.quantity || '', this.dataUnit(s), bands, bands ? style.levels : 0,
                d.scale || null, Array.from(ser.knots), d.ticks || []]);
            const b = byKey.get(key);
            if (b) {
                b.names.push(s.name);
                return;
            }
            const bar = { index: i, names: [s.name], bands, levels: style.levels, canvas: this.ui.bars.appendChild(document.createElement('canvas')) };
            byKey.set(key, bar);
            bars.push(bar);
        });
        return bars;
    }

    // A surface's data's unit (META.unit for pages without data.unit).
    dataUnit(s) {
        return (s.data && s.data.unit) || this.meta.unit || '';
    }

    // An electrode's name is dimmed when the electrode faces away from the viewer: the normal of
    // the nearest node of any surface (within 5% of the box's diagonal) points away from the eye.
    electrodeNormals(blobs) {
        const tol = 0.05 * this.view3d.diag;
        return (this.meta.electrodes || []).map((e) => {
            let best = tol * tol, n = null, surf = -1;
            this.meta.surfaces.forEach((s, si) => {
                if (s.layer) return; // the model's surfaces only
                const p = blobs[s.points], nr = blobs[s.normals];
                for (let i = 0; i < s.nodes; i++) {
                    const dx = p[3 * i] - e.position[0], dy = p[3 * i + 1] - e.position[1], dz = p[3 * i + 2] - e.position[2];
                    const d = dx * dx + dy * dy + dz * dz;
                    if (d < best) {
                        best = d;
                        n = [nr[3 * i], nr[3 * i + 1], nr[3 * i + 2]];
                        surf = si;
                    }
                }
            });
            return { n, surf };
        });
    }

    letterColor() {
        const bg = this.meta.background || [1, 1, 1, 1];
        const lum = 0.299 * bg[0] + 0.587 * bg[1] + 0.114 * bg[2];
        const dark = bg[3] < 0.5 || lum > 0.5; // dark letters on a light background, with a halo over the surfaces
        for (const l of this.ui.letters) {
            l.style.color = dark ? '#111' : '#f4f4f4';
            l.style.textShadow = dark ? '0 0 3px #fff, 0 0 2px #fff' : '0 0 3px #000, 0 0 2px #000';
        }
        this.ui.view.style.background = `rgba(${bg.slice(0, 3).map((x) => Math.round(255 * x)).join(',')},${bg[3]})`;
    }

    // ---------------------------------------------------------------- controls

    wire() {
        const ui = this.ui;
        ui.surfaces.forEach(({ box, op }, i) => {
            box.addEventListener('change', () => this.setSurface(i, { visible: box.checked }));
            op.addEventListener('input', () => this.setSurface(i, { opacity: Number(op.value) }));
        });
        if (ui.electrodes) ui.electrodes.addEventListener('change', () => this.setElectrodes(ui.electrodes.checked));
        if (ui.scanPlane) ui.scanPlane.addEventListener('change', () => this.setPlanes(ui.scanPlane.checked));
        for (const [name, b] of Object.entries(ui.viewButtons)) b.addEventListener('click', () => this.setView(name));
        ui.reset.addEventListener('click', () => this.setView(this.initialView()));
        ui.slider.addEventListener('input', () => this.setFrame(Number(ui.slider.value)));
        ui.play.addEventListener('click', () => this.togglePlay());
        window.addEventListener('resize', () => {
            if (!this.userSized) this.fitSize();
            this.layoutPlots();
        });
        this.wirePointer();
    }

    wirePointer() {
        const v = this.ui.view;
        let down = null;
        v.addEventListener('pointerdown', (ev) => {
            if (ev.button !== 0) return;
            v.setPointerCapture(ev.pointerId);
            down = { x: ev.clientX, y: ev.clientY, lx: ev.clientX, ly: ev.clientY, drag: false };
        });
        v.addEventListener('pointermove', (ev) => {
            if (!down) return;
            if (!down.drag && Math.hypot(ev.clientX - down.x, ev.clientY - down.y) > DRAG_SLOP) {
                down.drag = true;
                v.classList.add('thx-dragging');
            }
            if (down.drag) {
                const dx = ev.clientX - down.lx, dy = ev.clientY - down.ly;
                down.lx = ev.clientX;
                down.ly = ev.clientY;
                this.setCamera(orbit(this.cam, dx, dy, this.h), false);
            }
        });
        const up = (ev) => {
            if (!down) return;
            const wasDrag = down.drag;
            down = null;
            v.classList.remove('thx-dragging');
            if (!wasDrag && ev.type === 'pointerup') {
                const r = this.view3d.canvas.getBoundingClientRect();
                this.pickAt(ev.clientX - r.left, ev.clientY - r.top);
            }
        };
        v.addEventListener('pointerup', up);
        v.addEventListener('pointercancel', up);
        v.addEventListener('wheel', (ev) => {
            ev.preventDefault();
            const d = ev.deltaMode === 1 ? ev.deltaY * 16 : ev.deltaMode === 2 ? ev.deltaY * 400 : ev.deltaY;
            this.setCamera(zoom(this.cam, Math.exp(Math.max(-1, Math.min(1, d * 0.0015)))), false);
        }, { passive: false });
    }

    togglePlay() {
        this.playing = !this.playing;
        this.ui.play.textContent = this.playing ? 'pause' : 'play';
        this.ui.play.classList.toggle('thx-on', this.playing);
        if (!this.playing) return;
        let last = performance.now(), acc = 0;
        const step = (now) => {
            if (!this.playing) return;
            acc += ((now - last) * PLAY_FPS) / 1000;
            last = now;
            const k = Math.floor(acc);
            if (k > 0) {
                acc -= k;
                this.setFrame((this.frame + k) % this.M);
            }
            requestAnimationFrame(step);
        };
        requestAnimationFrame(step);
    }

    // ---------------------------------------------------------------- state

    // The view shown first (META.view, a name).
    initialView() {
        const v = this.meta.view;
        const name = typeof v === 'string' ? v : v && v.name;
        return VIEW_NAMES.includes(name) ? name : 'anterior';
    }

    // The camera for the current size: render's own (META.camera) at META.size in the first view,
    // else render's standard view (META.views[name]) with thx_camera_view's height for the aspect.
    standardCamera(name) {
        const m = this.meta;
        if (m.camera && name === this.initialView() && m.size && this.w === m.size[0] && this.h === m.size[1])
            return copyCamera(m.camera);
        if (m.views && m.views[name]) return cameraFromView(m.views[name], this.w / this.h);
        const box = m.view && m.view.box ? m.view.box : this.view3d.box; // the box's axes as the anatomical ones
        return viewCamera(name, box.lo, box.hi, this.w / this.h);
    }

    setCamera(cam, standard) {
        this.cam = cam;
        this.standard = standard;
        this.view3d.setCamera(cam);
        for (const [n, b] of Object.entries(this.ui.viewButtons)) b.classList.toggle('thx-on', standard && n === this.viewName);
        this.updateOverlays();
        this.requestDraw();
    }

    setView(name, now = false) {
        if (!VIEW_NAMES.includes(name)) throw new Error(`thorax: unknown view "${name}" (one of ${VIEW_NAMES.join(', ')})`);
        this.viewName = name;
        this.setCamera(this.standardCamera(name), true);
        if (now) this.drawNow();
    }

    // The 3D view at w x h CSS pixels (rendered at devicePixelRatio).
    setSize(w, h, now = false) {
        if (now) this.userSized = true;
        this.w = Math.max(16, Math.round(w));
        this.h = Math.max(16, Math.round(h));
        this.ui.view.style.width = `${this.w}px`;
        this.ui.view.style.height = `${this.h}px`;
        this.view3d.setSize(this.w, this.h, window.devicePixelRatio || 1);
        if (this.standard || !this.cam) this.setCamera(this.standardCamera(this.viewName), true);
        else this.setCamera(this.cam, false);
        this.drawBars();
        if (now) this.drawNow();
    }

    // META.size, narrowed to the page's width.
    fitSize() {
        const [W, H] = this.meta.size || [800, 600];
        const avail = Math.max(200, this.ui.main.clientWidth - 92);
        const w = Math.min(W, avail);
        this.setSize(w, Math.round((H * w) / W));
    }

    setFrame(f, now = false) {
        f = Math.round(Number(f));
        if (!Number.isFinite(f)) throw new Error(`thorax: frame ${f}`);
        f = Math.min(Math.max(f, 0), this.M - 1);
        this.frame = f;
        this.view3d.setFrame(f);
        this.ui.slider.value = String(f);
        const unit = this.meta.time_unit || '';
        this.ui.readout.textContent = `t = ${fmtTime(this.time[f])}${unit ? ' ' + unit : ''} (frame ${f + 1} of ${this.M})`;
        if (this.leadsPlot) this.leadsPlot.setFrame(f);
        this.nodePlot.setFrame(f);
        this.renderPicked();
        if (this.bars.some((b) => this.series[b.index].F > 1)) this.drawBars();
        if (now) this.drawNow();
        else this.requestDraw();
        return f;
    }

    setElectrodes(on) {
        this.electrodesOn = on;
        if (this.ui.electrodes) this.ui.electrodes.checked = on;
        this.view3d.setElectrodesVisible(on);
        this.updateLabels();
        this.requestDraw();
    }

    setPlanes(on) {
        if (this.ui.scanPlane) this.ui.scanPlane.checked = on;
        this.view3d.setPlanesVisible(on);
        this.requestDraw();
    }

    surfaceIndex(s) {
        if (typeof s === 'number' && s >= 0 && s < this.meta.surfaces.length) return s;
        const i = this.meta.surfaces.findIndex((q) => q.name === s);
        if (i < 0) throw new Error(`thorax: no surface "${s}"`);
        return i;
    }

    setSurface(name, { visible, opacity }, now = false) {
        if (name === 'electrodes' && !this.meta.surfaces.some((q) => q.name === name)) {
            // Not a surface: the electrodes' layer (its checkbox), so that tests can hide it.
            if (visible !== undefined) this.setElectrodes(!!visible);
            if (now) this.drawNow();
            return;
        }
        if (name === 'scan plane' && !this.meta.surfaces.some((q) => q.name === name)) {
            // Not a surface either: the scan's planes (their checkbox).
            if (visible !== undefined) this.setPlanes(!!visible);
            if (now) this.drawNow();
            return;
        }
        const i = this.surfaceIndex(name);
        this.view3d.setSurface(i, { visible, opacity });
        const s = this.view3d.surfaces[i], c = this.ui.surfaces[i];
        c.box.checked = s.visible;
        c.op.value = String(s.opacity);
        c.opv.textContent = `${Math.round(s.opacity * 100)}%`;
        this.updateOverlays();
        if (now) this.drawNow();
        else this.requestDraw();
    }

    // ---------------------------------------------------------------- picking and plots

    pickAt(x, y) {
        const hit = this.view3d.pick(x, y);
        if (!hit) return null;
        const s = this.meta.surfaces[hit.surface];
        const series = this.series[hit.surface];
        this.picked = { surface: hit.surface, node: hit.node, values: series ? series.nodeSeries(hit.node) : null };
        this.view3d.setMark(hit.surface, hit.node);
        const title = `${s.name} node ${hit.node + 1} (1-based)` + (s.data && s.data.quantity ? `: ${s.data.quantity}` : '');
        if (series) this.nodePlot.setSeries(this.picked.values, title, this.dataUnit(s));
        else this.nodePlot.setSeries(null, '');
        this.renderPicked();
        this.drawNow();
        return { surface: s.name, node: hit.node };
    }

    renderPicked() {
        const p = this.picked, el = this.ui.picked;
        if (!p) {
            el.textContent = 'none: click a surface';
            return;
        }
        const s = this.meta.surfaces[p.surface];
        const v = p.values ? p.values[this.frame] : NaN;
        el.textContent = `${s.name} node ${p.node + 1} (1-based)` +
            (p.values ? `: ${Number.isNaN(v) ? 'no value' : fmtG(v, 4) + ' ' + this.dataUnit(s)}` : ': no data');
    }

    nodeSeries(surface, node) {
        const i = this.surfaceIndex(surface);
        const s = this.series[i];
        if (!s) return null;
        if (!(node >= 0 && node < s.N)) throw new Error(`thorax: surface "${this.meta.surfaces[i].name}" has no node ${node}`);
        return s.nodeSeries(node);
    }

    plotted() {
        return this.picked && this.picked.values ? Float64Array.from(this.picked.values) : null;
    }

    marker() {
        return this.leadsPlot ? this.leadsPlot.frame : null;
    }

    clickLeads(x) {
        if (!this.leadsPlot) return null;
        const p = this.leadsPlot.panels[0];
        this.leadsPlot.click(x, p ? p.y + p.h / 2 : undefined);
        this.drawNow();
        return this.frame;
    }

    layoutPlots() {
        const width = Math.max(300, this.ui.root.clientWidth - 32);
        if (this.leadsPlot) this.leadsPlot.layout(width);
        this.nodePlot.layout(width);
    }

    drawBars() {
        const many = this.bars.length > 1;
        for (const b of this.bars) {
            const s = this.meta.surfaces[b.index], d = s.data, cm = this.meta.colormaps[d.colormap];
            drawColorBar(b.canvas, {
                rgb: this.cmapBytes[d.colormap],
                n: cm.n,
                series: this.series[b.index],
                frame: s.layer ? 0 : this.frame, // a layer's one scale
                ticks: d.ticks,
                bands: b.bands,
                levels: b.levels,
                quantity: d.quantity || '',
                unit: this.dataUnit(s),
                title: many ? b.names.join(', ') : '',
                height: Math.min(320, Math.round(this.h * 0.7 / this.bars.length)),
            });
        }
    }

    // ---------------------------------------------------------------- overlays

    updateOverlays() {
        if (!this.cam) return;
        const fr = this.meta.frame || this.meta.view || {}; // the anatomical frame
        const L = orientationLetters(this.cam, fr.ax || [0, 1, 2], fr.sg || [1, 1, 1]);
        this.ui.letters.forEach((el, k) => (el.textContent = L[k]));
        this.updateLabels();
    }

    updateLabels() {
        const box = this.ui.labels, els = this.meta.electrodes || [];
        if (!this.labelEls) {
            this.labelEls = els.map((e) => {
                const d = document.createElement('div');
                d.className = 'thx-elabel';
                d.textContent = e.name;
                box.appendChild(d);
                return d;
            });
        }
        const f = cameraFrame(this.cam);
        els.forEach((e, i) => {
            const d = this.labelEls[i];
            const p = projectPoint(this.cam, this.w, this.h, e.position);
            const nn = this.nearestNormals[i];
            const surf = nn.surf >= 0 ? this.view3d.surfaces[nn.surf] : null;
            const facing = !nn.n || !f || !surf || !surf.drawn.visible || surf.opacity < 1 ||
                nn.n[0] * f.back[0] + nn.n[1] * f.back[1] + nn.n[2] * f.back[2] >= 0;
            // As render's names: beside the sphere, dimmed when the electrode is behind the surface.
            const show = this.electrodesOn && p && p.x >= 0 && p.x < this.w && p.y >= 0 && p.y < this.h;
            d.style.display = show ? 'block' : 'none';
            d.classList.toggle('thx-behind', !facing);
            if (show) d.style.transform = `translate(${Math.round(p.x + 8)}px, ${Math.round(p.y - 8)}px)`;
        });
    }

    // ---------------------------------------------------------------- drawing

    // A frame step (playing, the slider, turning, zooming): drawn at the next animation frame, as it
    // is; on a software rasterizer drawn again smoothed (render's FXAA) once nothing has changed for
    // SETTLE_MS.
    requestDraw() {
        if (this.drawPending) return;
        this.drawPending = true;
        requestAnimationFrame(() => {
            if (this.drawPending) this.drawNow(false);
        });
    }

    // Draws now: smoothed (the picture to keep), or as a frame step with the smoothed one to follow.
    drawNow(smooth = true) {
        this.drawPending = false;
        clearTimeout(this.settleTimer);
        this.settleTimer = null;
        this.view3d.render(smooth);
        if (!smooth && this.view3d.fxaa)
            this.settleTimer = setTimeout(() => {
                this.settleTimer = null;
                if (!this.view3d.smoothed && !this.drawPending) this.drawNow(true);
            }, SETTLE_MS);
    }

    canvasPixels() {
        this.drawNow();
        return this.view3d.pixels().data;
    }

    // Mean milliseconds per frame step over n steps, each drawn as while playing and waited for
    // (on a software rasterizer unsmoothed; the picture is smoothed once still).
    benchFrames(n) {
        n = Math.max(1, Math.round(n));
        const t0 = performance.now();
        for (let i = 0; i < n; i++) {
            this.setFrame((this.frame + 1) % this.M);
            this.drawNow(false);
            this.view3d.finish();
        }
        return (performance.now() - t0) / n;
    }
}

async function start() {
    let root = document.getElementById('thorax');
    if (!root) {
        root = document.createElement('div');
        root.id = 'thorax';
        document.body.appendChild(root);
    }
    const waiting = document.getElementById('thorax-waiting'); // the page's text until the viewer starts
    if (waiting) waiting.remove();
    let meta = null, ui = null;
    const fail = (e) => {
        const msg = e instanceof PageError ? e.message : (e && e.message) || String(e);
        console.error(`thorax: ${msg}`);
        showError(ui || buildUI(root, meta || {}), msg);
        rejectReady(new Error(msg));
        window.thorax = hooks;
    };
    hooks.timings.script_ms = performance.now();
    try {
        meta = readMeta(document);
        hooks.meta = meta;
        ui = buildUI(root, meta);
        const blobs = await decodeBlobs(document, meta);
        const M = meta.frames;
        // A layer's data has one frame (it was made for frame s.layer.frame).
        const series = meta.surfaces.map((s) => (s.data ? new Series(s.data, blobs, s.layer ? 1 : M, s.nodes) : null));
        hooks.timings.load_ms = performance.now();
        buildMain(ui, meta);
        app = new App(ui, meta, blobs, series);
        hooks.timings.scene_ms = performance.now();
        hooks.timings.context_ms = app.view3d.contextMs;
        app.fitSize();
        app.layoutPlots();
        app.setFrame(Math.min(Math.max(meta.initial_frame | 0, 0), M - 1));
        // As a frame step: on a software rasterizer the smoothed picture (FXAA, whose first use
        // costs Chromium's SwiftShader 100 ms) follows once still, as after any step.
        app.drawNow(false);
        app.view3d.finish();
        hooks.timings.first_picture_ms = performance.now();
        // shown: the second animation frame after the first picture, whose frame the compositor has
        // taken (what a person sees, give or take the display's refresh).
        requestAnimationFrame(() => requestAnimationFrame(() => (hooks.timings.shown_ms = performance.now())));
        window.thorax = hooks;
        resolveReady(hooks);
    } catch (e) {
        app = null;
        fail(e);
    }
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
else start();
