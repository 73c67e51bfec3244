// The 2D plots on canvases: the leads (a panel per lead in a grid like a 12-lead sheet), the picked
// node's series, both with the current frame's marker, and the colour bar.
import { fmtG, fmtTime } from './format.js';

const INK = '#222';
const GRID = '#f0c8c8';
const AXIS = '#d08c8c';
const MARKER = '#d0102a';
const FONT = '11px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif';

// A canvas's 2D context, drawn on the CPU (`willReadFrequently`: Chromium then keeps the canvas in
// memory). The plots are a few thousand line segments and some text, cheap on the CPU; on the GPU
// a browser's first page compiles its 2D pipelines first, and on a software GL (SwiftShader) that
// took 450 ms of Chromium's GPU process, ahead of the 3D view's first picture (docs/design/web.md).
function context2d(canvas) {
    return canvas.getContext('2d', { willReadFrequently: true });
}

// A canvas at CSS size w x h, drawn at devicePixelRatio; returns its 2D context scaled to CSS px.
function sizeCanvas(canvas, w, h) {
    const dpr = window.devicePixelRatio || 1;
    canvas.style.width = `${w}px`;
    canvas.style.height = `${h}px`;
    canvas.width = Math.max(1, Math.round(w * dpr));
    canvas.height = Math.max(1, Math.round(h * dpr));
    const ctx = context2d(canvas);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return ctx;
}

function finiteRange(arrays) {
    let lo = Infinity, hi = -Infinity;
    for (const a of arrays)
        for (let i = 0; i < a.length; i++) {
            const v = a[i];
            if (v < lo) lo = v;
            if (v > hi) hi = v;
        }
    if (!(lo <= hi)) return [-1, 1];
    if (hi - lo < 1e-12 * Math.max(1, Math.abs(hi))) {
        const d = Math.max(Math.abs(hi) * 0.1, 1e-6);
        return [lo - d, hi + d];
    }
    const pad = 0.06 * (hi - lo);
    return [lo - pad, hi + pad];
}

// Nearest frame to time value t (time ascending).
function frameAtTime(time, t) {
    const M = time.length;
    if (M <= 1) return 0;
    let a = 0, b = M - 1;
    if (t <= time[0]) return 0;
    if (t >= time[b]) return b;
    while (b - a > 1) {
        const m = (a + b) >> 1;
        if (time[m] <= t) a = m;
        else b = m;
    }
    return t - time[a] <= time[b] - t ? a : b;
}

// Series panels sharing one time axis: a grid of rects, traces drawn once into an offscreen canvas,
// the marker drawn over them per frame.
class TracePlot {
    constructor(canvas, time, onSeek) {
        this.canvas = canvas;
        this.time = time;
        this.t0 = time[0];
        this.t1 = time[time.length - 1];
        if (!(this.t1 > this.t0)) this.t1 = this.t0 + 1;
        this.frame = 0;
        this.panels = [];
        this.back = document.createElement('canvas');
        this.w = 0;
        this.h = 0;
        canvas.addEventListener('click', (ev) => {
            const r = canvas.getBoundingClientRect();
            this.click(ev.clientX - r.left, ev.clientY - r.top);
        });
        this.onSeek = onSeek;
    }

    xOf(p, t) {
        return p.x + ((t - this.t0) / (this.t1 - this.t0)) * p.w;
    }

    // The frame at CSS x (in the panel under (x, y), or the first panel whose columns hold x).
    frameAt(x, y) {
        let p = this.panels.find((q) => x >= q.x && x <= q.x + q.w && (y === undefined || (y >= q.y && y <= q.y + q.h)));
        if (!p) p = this.panels.find((q) => x >= q.x - 8 && x <= q.x + q.w + 8);
        if (!p) return null;
        const u = Math.min(Math.max((x - p.x) / p.w, 0), 1);
        return frameAtTime(this.time, this.t0 + u * (this.t1 - this.t0));
    }

    click(x, y) {
        const f = this.frameAt(x, y);
        if (f !== null && this.onSeek) this.onSeek(f);
        return f;
    }

    // Draws a panel's frame, grid, zero line and trace into ctx.
    drawPanel(ctx, p, values, lo, hi, name, yLabels, unit) {
        const yOf = (v) => p.y + p.h - ((v - lo) / (hi - lo)) * p.h;
        ctx.save();
        ctx.beginPath();
        ctx.rect(p.x, p.y, p.w, p.h);
        ctx.clip();
        ctx.fillStyle = '#fff';
        ctx.fillRect(p.x, p.y, p.w, p.h);
        // Faint vertical grid at ten divisions of the time axis.
        ctx.strokeStyle = GRID;
        ctx.lineWidth = 1;
        ctx.beginPath();
        for (let j = 1; j < 10; j++) {
            const x = Math.round(p.x + (j * p.w) / 10) + 0.5;
            ctx.moveTo(x, p.y);
            ctx.lineTo(x, p.y + p.h);
        }
        ctx.stroke();
        if (lo < 0 && hi > 0) {
            ctx.strokeStyle = AXIS;
            ctx.beginPath();
            const y0 = Math.round(yOf(0)) + 0.5;
            ctx.moveTo(p.x, y0);
            ctx.lineTo(p.x + p.w, y0);
            ctx.stroke();
        }
        // The trace, broken at NaN.
        ctx.strokeStyle = INK;
        ctx.lineWidth = 1.2;
        ctx.lineJoin = 'round';
        ctx.beginPath();
        let pen = false;
        for (let f = 0; f < values.length; f++) {
            const v = values[f];
            if (!Number.isFinite(v)) {
                pen = false;
                continue;
            }
            const x = this.xOf(p, this.time[f]), y = yOf(v);
            if (pen) ctx.lineTo(x, y);
            else ctx.moveTo(x, y);
            pen = true;
        }
        ctx.stroke();
        ctx.restore();
        ctx.strokeStyle = '#bbb';
        ctx.lineWidth = 1;
        ctx.strokeRect(p.x + 0.5, p.y + 0.5, p.w - 1, p.h - 1);
        ctx.font = FONT;
        ctx.fillStyle = INK;
        ctx.textBaseline = 'top';
        ctx.textAlign = 'left';
        if (name) ctx.fillText(name, p.x + 4, p.y + 3);
        if (yLabels) {
            ctx.textAlign = 'right';
            ctx.textBaseline = 'middle';
            const placed = []; // in the order given; a label closer than 14 px to one placed is left out
            for (const v of yLabels) {
                const y = yOf(v);
                if (placed.some((q) => Math.abs(q - y) < 14)) continue;
                placed.push(y);
                ctx.fillText(fmtG(v, 3), p.x - 4, y);
            }
        }
        if (unit) { // in the margin above the panel's top left corner
            ctx.textAlign = 'right';
            ctx.textBaseline = 'bottom';
            ctx.fillText(unit, p.x - 4, p.y - 1);
        }
    }

    drawTimeLabels(ctx, p, unit) {
        ctx.font = FONT;
        ctx.fillStyle = '#555';
        ctx.textBaseline = 'top';
        ctx.textAlign = 'left';
        ctx.fillText(`${fmtTime(this.t0)}`, p.x, p.y + p.h + 2);
        ctx.textAlign = 'right';
        ctx.fillText(`${fmtTime(this.t1)} ${unit}`, p.x + p.w, p.y + p.h + 2);
    }

    // The traces (offscreen) and then the marker.
    present() {
        const ctx = context2d(this.canvas);
        const dpr = window.devicePixelRatio || 1;
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
        ctx.drawImage(this.back, 0, 0);
        ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
        ctx.strokeStyle = MARKER;
        ctx.lineWidth = 1.5;
        ctx.beginPath();
        for (const p of this.panels) {
            const x = this.xOf(p, this.time[this.frame]);
            ctx.moveTo(x, p.y);
            ctx.lineTo(x, p.y + p.h);
        }
        ctx.stroke();
    }

    setFrame(f) {
        this.frame = f;
        this.present();
    }
}

// The leads: L panels, column-major in a grid (12 leads: 4 columns of 3, as a 12-lead sheet), one
// amplitude scale for all.
export class LeadsPlot extends TracePlot {
    constructor(canvas, leads, time, timeUnit, unit, onSeek) {
        super(canvas, time, onSeek);
        this.leads = leads;
        this.timeUnit = timeUnit;
        this.unit = unit;
        this.range = finiteRange(leads.map((l) => l.values));
    }

    layout(width) {
        const L = this.leads.length;
        const cols = L >= 12 ? 4 : L > 6 ? 2 : 1;
        const rows = Math.ceil(L / cols);
        const left = 44, right = 8, top = 16, gapX = 10, gapY = 6, bottom = 18;
        const ph = Math.max(56, Math.min(90, Math.round(width / cols / 3.2)));
        const pw = Math.floor((width - left - right - gapX * (cols - 1)) / cols);
        const h = top + rows * ph + (rows - 1) * gapY + bottom;
        this.panels = [];
        for (let i = 0; i < L; i++) {
            const c = Math.floor(i / rows), r = i % rows;
            this.panels.push({ x: left + c * (pw + gapX), y: top + r * (ph + gapY), w: pw, h: ph, col: c, row: r });
        }
        this.w = width;
        this.h = h;
        sizeCanvas(this.canvas, width, h);
        const ctx = sizeCanvas(this.back, width, h);
        const [lo, hi] = this.range;
        this.panels.forEach((p, i) => {
            const first = p.col === 0;
            this.drawPanel(ctx, p, this.leads[i].values, lo, hi, this.leads[i].name, first ? this.yTicks(lo, hi) : null,
                first && p.row === 0 ? this.unit : null);
            if (p.row === rows - 1 || i === L - 1) this.drawTimeLabels(ctx, p, this.timeUnit);
        });
        this.present();
    }

    yTicks(lo, hi) {
        const out = [];
        if (lo < 0 && hi > 0) out.push(0);
        const m = Math.max(Math.abs(lo), Math.abs(hi));
        const step = Math.pow(10, Math.floor(Math.log10(m)));
        const a = Math.floor(hi / step) * step, b = Math.ceil(lo / step) * step;
        if (a > 0 && (hi - a) / (hi - lo) < 0.5) out.push(a);
        if (b < 0 && (b - lo) / (hi - lo) < 0.5) out.push(b);
        return out;
    }
}

// The picked node's series: one panel, titled with the node's name.
export class NodePlot extends TracePlot {
    constructor(canvas, time, timeUnit, unit, onSeek) {
        super(canvas, time, onSeek);
        this.timeUnit = timeUnit;
        this.unit = unit;
        this.values = null;
        this.title = '';
    }

    // The series (or null), its title and its unit (the picked surface's data's).
    setSeries(values, title, unit) {
        this.values = values;
        this.title = title;
        if (unit !== undefined) this.unit = unit;
        if (this.w) this.layout(this.w);
    }

    layout(width) {
        const h = 150, left = 44, right = 8, top = 18, bottom = 18;
        const p = { x: left, y: top, w: Math.max(20, width - left - right), h: h - top - bottom };
        this.panels = this.values ? [p] : [];
        this.w = width;
        this.h = h;
        sizeCanvas(this.canvas, width, h);
        const ctx = sizeCanvas(this.back, width, h);
        ctx.font = FONT;
        ctx.fillStyle = INK;
        ctx.textBaseline = 'top';
        if (!this.values) {
            ctx.fillStyle = '#777';
            ctx.fillText('Click a surface in the 3D view to plot a node\u2019s series here.', left, top + 4);
        } else {
            const [lo, hi] = finiteRange([this.values]);
            ctx.fillText(this.title, left, 2);
            const ticks = [lo + 0.06 * (hi - lo) / 1.12, hi - 0.06 * (hi - lo) / 1.12]; // the series' min and max
            if (lo < 0 && hi > 0) ticks.push(0);
            this.drawPanel(ctx, p, this.values, lo, hi, '', ticks, this.unit);
            this.drawTimeLabels(ctx, p, this.timeUnit);
        }
        this.present();
    }
}

// The colour bar: the colour map as render reads it (linear between texels, banded for the bands
// styles), its ticks at their t, labelled; above it, as render's, the surfaces it is for (title,
// when there are several bars), what is shown (quantity) and the unit.
export function drawColorBar(canvas, { rgb, n, series, frame, ticks, bands, levels, quantity, unit, title, height }) {
    const head = [title, quantity, unit ? `(${unit})` : ''].filter(Boolean);
    const barW = 16, lineH = 13, top = 8 + lineH * head.length, bottom = 10;
    const measure = context2d(canvas);
    measure.font = FONT;
    const textW = Math.max(0, ...head.map((t) => Math.ceil(measure.measureText(t).width) + 4));
    const w = Math.max(78, textW);
    const h = Math.max(80, height) + lineH * Math.max(0, head.length - 1);
    const ctx = sizeCanvas(canvas, w, h);
    const bh = h - top - bottom, x0 = 6;
    ctx.clearRect(0, 0, w, h);
    const nb = Math.max(levels | 0, 1);
    for (let y = 0; y < bh; y++) {
        let t = 1 - (y + 0.5) / bh;
        if (bands) t = (Math.min(Math.floor(t * nb), nb - 1) + 0.5) / nb;
        const u = t * (n - 1), i = Math.min(Math.floor(u), n - 2), a = u - i;
        const c = [0, 1, 2].map((k) => Math.round(rgb[3 * i + k] * (1 - a) + rgb[3 * (i + 1) + k] * a));
        ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
        ctx.fillRect(x0, top + y, barW, 1);
    }
    ctx.strokeStyle = '#444';
    ctx.lineWidth = 1;
    ctx.strokeRect(x0 + 0.5, top + 0.5, barW - 1, bh - 1);
    ctx.font = FONT;
    ctx.fillStyle = INK;
    ctx.textAlign = 'left';
    ctx.textBaseline = 'middle';
    // Every tick marked; labels thinned to one per 13 px, the ends and zero first.
    const marks = (ticks || []).map((v) => ({ v, y: Math.round(top + (1 - series.t(v, frame)) * bh) + 0.5 }))
        .filter((m) => m.y >= top - 1 && m.y <= top + bh + 1);
    ctx.beginPath();
    for (const m of marks) {
        ctx.moveTo(x0 + barW - 4, m.y);
        ctx.lineTo(x0 + barW + 3, m.y);
    }
    ctx.stroke();
    const order = marks.map((m, i) => ({ m, rank: i === 0 || i === marks.length - 1 ? 0 : m.v === 0 ? 1 : 2 + Math.abs(i - marks.length / 2) / marks.length }))
        .sort((a, b) => a.rank - b.rank);
    const placed = [];
    for (const { m } of order) {
        if (placed.some((y) => Math.abs(y - m.y) < 13)) continue;
        placed.push(m.y);
        ctx.fillText(fmtG(m.v, 3), x0 + barW + 6, m.y);
    }
    ctx.textBaseline = 'top';
    head.forEach((t, k) => ctx.fillText(t, 2, 2 + lineH * k));
}
