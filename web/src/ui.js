// The page's DOM and style: plain elements, no framework. buildUI makes the skeleton inside
// <div id="thorax"> and returns the elements main.js wires up.
import { VIEW_NAMES } from './camera.js';
import { fmtTime } from './format.js';

const CSS = `
.thx { font: 14px/1.4 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif; color: #222;
  max-width: 1400px; margin: 0 auto; padding: 12px 16px 24px; box-sizing: border-box; }
.thx * { box-sizing: border-box; }
.thx h1 { font-size: 20px; margin: 0 0 2px; font-weight: 600; }
.thx h2 { font-size: 15px; margin: 14px 0 4px; font-weight: 600; }
.thx h3 { font-size: 12px; margin: 10px 0 4px; font-weight: 600; text-transform: uppercase; letter-spacing: .04em; color: #555; }
.thx-sub { color: #666; font-size: 12px; margin: 0 0 10px; word-break: break-all; }
.thx-error { display: none; background: #fde8e8; border: 1px solid #e0a0a0; color: #8a1010; padding: 10px 12px;
  border-radius: 4px; margin: 8px 0; white-space: pre-wrap; }
.thx-loading { color: #666; padding: 20px 0; }
.thx-main { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; }
.thx-left { display: flex; flex-direction: column; min-width: 0; }
.thx-viewwrap { display: flex; gap: 6px; align-items: flex-start; }
.thx-view { position: relative; overflow: hidden; border: 1px solid #ccc; touch-action: none; cursor: grab; flex: none; }
.thx-view.thx-dragging { cursor: grabbing; }
.thx-view canvas { display: block; }
.thx-letter { position: absolute; font: bold 15px/1 system-ui, sans-serif; pointer-events: none; user-select: none; }
.thx-letter.l { left: 6px; top: 50%; transform: translateY(-50%); }
.thx-letter.r { right: 6px; top: 50%; transform: translateY(-50%); }
.thx-letter.t { top: 5px; left: 50%; transform: translateX(-50%); }
.thx-letter.b { bottom: 6px; left: 50%; transform: translateX(-50%); }
.thx-labels { position: absolute; inset: 0; pointer-events: none; }
.thx-elabel { position: absolute; left: 0; top: 0; font: 12px/1 system-ui, sans-serif; color: #fff; white-space: nowrap;
  text-shadow: 0 0 2px #000, 1px 1px 1px #000; }
.thx-elabel.thx-behind { color: #aaa; }
.thx-bars { display: flex; flex-direction: column; gap: 8px; }
.thx-side { flex: 1 1 230px; min-width: 220px; max-width: 360px; }
.thx-surf { padding: 3px 0; border-bottom: 1px solid #eee; }
.thx-surf label, .thx-check { display: flex; align-items: center; gap: 6px; }
.thx-surf label { font-weight: 500; }
.thx-surf .thx-role { color: #888; font-weight: normal; font-size: 12px; }
.thx-surf .thx-op { margin-left: 24px; display: flex; align-items: center; gap: 6px; font-size: 12px; color: #555; }
.thx-surf input[type=range] { flex: 1; min-width: 60px; }
.thx-views { display: flex; flex-wrap: wrap; gap: 4px; }
.thx button { font: inherit; font-size: 13px; padding: 3px 9px; border: 1px solid #aaa; border-radius: 3px;
  background: #f6f6f6; cursor: pointer; }
.thx button:hover { background: #ececec; }
.thx button.thx-on { background: #dde8f6; border-color: #7a9cc8; }
.thx-time { display: flex; align-items: center; gap: 10px; margin: 10px 0 4px; flex-wrap: wrap; }
.thx-time input[type=range] { flex: 1 1 300px; min-width: 160px; }
.thx-play { min-width: 64px; }
.thx-readout { font-variant-numeric: tabular-nums; min-width: 240px; }
.thx-plots canvas { display: block; cursor: crosshair; }
.thx-note { color: #777; font-size: 12px; margin-top: 14px; }
.thx-picked { font-size: 13px; color: #444; }
`;

function el(tag, attrs = {}, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs)) {
        if (k === 'class') e.className = v;
        else if (k === 'text') e.textContent = v;
        else e.setAttribute(k, v);
    }
    for (const c of children) if (c) e.append(c);
    return e;
}

// The skeleton, with a "loading" line until the data are decoded.
export function buildUI(root, meta) {
    root.classList.add('thx');
    root.append(el('style', { text: CSS }));
    const title = meta.title || 'thorax';
    root.append(el('h1', { text: title }));
    const src = meta.source || {};
    const bits = [meta.generator, src.model && `model ${src.model}`, src.solution && `solution ${src.solution}`,
        src.data && `data ${src.data}`].filter(Boolean);
    root.append(el('p', { class: 'thx-sub', text: bits.join(' \u00b7 ') }));
    const error = el('div', { class: 'thx-error', role: 'alert' });
    const loading = el('div', { class: 'thx-loading', text: 'Loading the data\u2026' });
    root.append(error, loading);
    return { root, error, loading };
}

export function showError(ui, message) {
    if (ui.loading) ui.loading.remove();
    ui.error.style.display = 'block';
    ui.error.textContent = `This page cannot be shown: ${message}`;
}

// What a layer's row says beside its name: the time it was made for (it does not follow the frame),
// or, for a layer without data (the scan's contour lines), what it is.
function layerNote(s, meta) {
    if (!s.data) return s.mode === 'wire' ? '(contour lines)' : '(layer)';
    const unit = meta.time_unit || '';
    const t = Number.isFinite(s.layer.time) ? s.layer.time : meta.time ? meta.time[s.layer.frame] : NaN;
    return `(at t = ${fmtTime(t)}${unit ? ' ' + unit : ''})`;
}

// The rest, once the data are in: the 3D view and its overlays, the colour bars, the controls, the
// time bar and the plots.
export function buildMain(ui, meta) {
    ui.loading.remove();
    const main = el('div', { class: 'thx-main' });
    const view = el('div', { class: 'thx-view', title: 'Drag to turn, wheel to zoom, click to pick a node' });
    const canvas = el('canvas', { class: 'thx-canvas' });
    const letters = ['l', 'r', 't', 'b'].map((c) => el('div', { class: `thx-letter ${c}` }));
    const labels = el('div', { class: 'thx-labels' });
    view.append(canvas, ...letters, labels);
    const bars = el('div', { class: 'thx-bars' });
    const viewwrap = el('div', { class: 'thx-viewwrap' }, view, bars);
    const left = el('div', { class: 'thx-left' }, viewwrap);

    const side = el('aside', { class: 'thx-side' });
    // The model's surfaces, then the layers (each made for one frame, said beside its name) and the
    // scan's planes; ui.surfaces is indexed as META.surfaces.
    const surfaceRow = (s) => {
        const box = el('input', { type: 'checkbox' });
        box.checked = s.visible !== false && s.mode !== 'hidden';
        if (s.mode === 'hidden') box.disabled = true;
        const note = s.layer ? layerNote(s, meta) : s.role && s.role !== s.name ? `(${s.role})` : '';
        const lab = el('label', {}, box, s.name, el('span', { class: 'thx-role', text: note }));
        if (s.layer) lab.title = 'A layer: drawn as it was made for that frame, whatever the frame shown';
        const op = el('input', { type: 'range', min: '0', max: '1', step: '0.01', 'aria-label': `${s.name} opacity` });
        op.value = String(s.opacity !== undefined ? s.opacity : 1);
        const opv = el('span', { text: `${Math.round(Number(op.value) * 100)}%` });
        return { row: el('div', { class: 'thx-surf' }, lab, el('div', { class: 'thx-op' }, 'opacity', op, opv)), box, op, opv };
    };
    const surfaces = meta.surfaces.map(surfaceRow);
    side.append(el('h3', { text: 'Surfaces' }));
    meta.surfaces.forEach((s, i) => !s.layer && side.append(surfaces[i].row));
    const planes = meta.planes && meta.planes.length ? meta.planes : null;
    let scanPlane = null;
    if (meta.surfaces.some((s) => s.layer) || planes) {
        side.append(el('h3', { text: 'Layers' }));
        meta.surfaces.forEach((s, i) => s.layer && side.append(surfaces[i].row));
        if (planes) {
            scanPlane = el('input', { type: 'checkbox' });
            scanPlane.checked = true;
            side.append(el('div', { class: 'thx-surf' }, el('label', {}, scanPlane, 'scan plane',
                el('span', { class: 'thx-role', text: planes.length > 1 ? `(${planes.length} planes)` : '' }))));
        }
    }
    let electrodes = null;
    if (meta.electrodes && meta.electrodes.length) {
        side.append(el('h3', { text: 'Electrodes' }));
        electrodes = el('input', { type: 'checkbox' });
        electrodes.checked = true;
        side.append(el('label', { class: 'thx-check' }, electrodes, `show the ${meta.electrodes.length} electrodes`));
    }
    side.append(el('h3', { text: 'View' }));
    const views = el('div', { class: 'thx-views' });
    const viewButtons = {};
    for (const v of VIEW_NAMES) {
        const b = el('button', { type: 'button', text: v });
        b.dataset.view = v;
        viewButtons[v] = b;
        views.append(b);
    }
    const reset = el('button', { type: 'button', text: 'reset view' });
    views.append(reset);
    side.append(views);
    const picked = el('div', { class: 'thx-picked' });
    side.append(el('h3', { text: 'Picked node' }), picked);
    main.append(left, side);
    ui.root.append(main);

    const M = meta.frames;
    const play = el('button', { type: 'button', class: 'thx-play', text: 'play' });
    const slider = el('input', { type: 'range', min: '0', max: String(Math.max(0, M - 1)), step: '1', 'aria-label': 'frame' });
    const readout = el('span', { class: 'thx-readout' });
    const time = el('div', { class: 'thx-time' }, play, slider, readout);
    if (M <= 1) { // a model without data: no time
        play.disabled = true;
        slider.disabled = true;
        time.style.display = 'none';
    }
    left.append(time); // under the view (and the page's first range input: the frame slider)
    const hasData = meta.surfaces.some((s) => s.data && !s.layer); // a series over the frames to plot

    const plots = el('section', { class: 'thx-plots' });
    let leadsCanvas = null;
    if (meta.leads) {
        plots.append(el('h2', { text: meta.leads.title || 'Leads' }));
        leadsCanvas = el('canvas', { title: 'Click to go to that time' });
        plots.append(leadsCanvas);
    }
    const nodeHead = el('h2', { text: 'Picked node' });
    const nodeCanvas = el('canvas', { title: 'Click to go to that time' });
    plots.append(nodeHead, nodeCanvas);
    if (!hasData) nodeHead.style.display = nodeCanvas.style.display = 'none'; // no series to plot
    ui.root.append(plots);
    const q = meta.quantization;
    if (q && hasData) {
        ui.root.append(el('p', { class: 'thx-note',
            text: `Values are stored with ${q.bits}-bit quantization: each is within \u00b1${q.max_error.toPrecision(3)} ${q.unit} of the solution's.` }));
    }
    return Object.assign(ui, { main, view, canvas, letters, labels, bars, side, surfaces, scanPlane, electrodes, viewButtons,
        reset, picked, play, slider, readout, leadsCanvas, nodeCanvas });
}
