// The page's data, version 1 (docs/design/web.md, "The page's data, version 1"): META, the blobs
// (base64, maybe deflate-raw) and the surfaces' series (16-bit codes, frame-major, frame deltas).

// render's t of a NaN value (src/render/render_internal.h NAN_T): |t| > 2 anywhere inside a
// triangle touching such a node, where the fragment shader shows the NaN colour.
export const NAN_T = 1.0e6;
export const NAN_CODE = 65535;

const TYPES = {
    float32: Float32Array,
    float64: Float64Array,
    uint32: Uint32Array,
    uint16: Uint16Array,
    uint8: Uint8Array,
};

export class PageError extends Error {
    constructor(message) {
        super(message);
        this.name = 'PageError';
    }
}

// META from <script type="application/json" id="thorax-page">.
export function readMeta(doc) {
    const el = doc.getElementById('thorax-page');
    if (!el) throw new PageError('this page has no data (no element "thorax-page")');
    let meta;
    try {
        meta = JSON.parse(el.textContent);
    } catch (e) {
        throw new PageError(`the page's data (META) is not valid JSON: ${e.message}`);
    }
    if (meta.format !== 'thorax-page') throw new PageError(`the page's data has format "${meta.format}", not "thorax-page"`);
    if (meta.version !== 1) throw new PageError(`the page's data is version ${meta.version}; this viewer reads version 1`);
    return meta;
}

function base64Bytes(text) {
    const s = text.replace(/\s+/g, '');
    if (typeof Uint8Array.fromBase64 === 'function') return Uint8Array.fromBase64(s);
    const bin = atob(s);
    const n = bin.length, out = new Uint8Array(n);
    for (let i = 0; i < n; i++) out[i] = bin.charCodeAt(i);
    return out;
}

async function inflateRaw(bytes) {
    if (typeof DecompressionStream !== 'function')
        throw new PageError('this browser has no DecompressionStream("deflate-raw") (Chromium 80+, Firefox 113+ have)');
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate-raw'));
    return new Response(stream).arrayBuffer();
}

// Blob k as a typed array of its META type and count, checked against data-bytes.
async function decodeBlob(doc, k, spec) {
    const el = doc.getElementById(`thorax-blob-${k}`);
    if (!el) throw new PageError(`blob ${k} is missing (no element "thorax-blob-${k}")`);
    const Type = TYPES[spec.type];
    if (!Type) throw new PageError(`blob ${k} has the unknown type "${spec.type}"`);
    const comp = el.getAttribute('data-compression') || 'none';
    const want = Number(el.getAttribute('data-bytes'));
    let raw;
    try {
        raw = base64Bytes(el.textContent);
    } catch (e) {
        throw new PageError(`blob ${k} is not valid base64: ${e.message}`);
    }
    let buf;
    if (comp === 'deflate-raw') {
        try {
            buf = await inflateRaw(raw);
        } catch (e) {
            throw new PageError(`blob ${k} does not inflate (deflate-raw): ${e.message}`);
        }
    } else if (comp === 'none') {
        buf = raw.buffer;
    } else {
        throw new PageError(`blob ${k} has the unknown compression "${comp}"`);
    }
    if (buf.byteLength !== want)
        throw new PageError(`blob ${k} holds ${buf.byteLength} bytes after decompression, data-bytes says ${want}`);
    if (buf.byteLength !== spec.count * Type.BYTES_PER_ELEMENT)
        throw new PageError(`blob ${k}: ${buf.byteLength} bytes are not ${spec.count} ${spec.type} values`);
    return new Type(buf);
}

// Every blob, decoded in parallel.
export async function decodeBlobs(doc, meta) {
    if (new Uint8Array(new Uint16Array([1]).buffer)[0] !== 1)
        throw new PageError('this viewer reads the little-endian blobs on little-endian machines only');
    const specs = meta.blobs || [];
    return Promise.all(specs.map((spec, k) => decodeBlob(doc, k, spec)));
}

// Piecewise-linear t(v) through the knots v[off .. off+K), t[off+K .. off+2K), clamped at the ends.
function knotT(kn, off, K, v) {
    const tOff = off + K;
    if (!(v > kn[off])) return kn[tOff];
    if (!(v < kn[off + K - 1])) return kn[tOff + K - 1];
    let a = 0, b = K - 1; // kn[off + a] < v < kn[off + b]
    while (b - a > 1) {
        const m = (a + b) >> 1;
        if (kn[off + m] <= v) a = m;
        else b = m;
    }
    const v0 = kn[off + a], v1 = kn[off + b], t0 = kn[tOff + a], t1 = kn[tOff + b];
    return v1 > v0 ? t0 + (v - v0) * (t1 - t0) / (v1 - v0) : t1;
}

// A surface's series: the codes reconstructed from the deltas once (a Uint16Array of M N, frame
// major), the value of a code, t per node for a frame, and the scale's t for the colour bar.
export class Series {
    constructor(data, blobs, M, N) {
        this.M = M;
        this.N = N;
        this.origin = data.origin;
        this.step = data.step;
        if (data.encoding !== 'u16-delta') throw new PageError(`unknown values encoding "${data.encoding}"`);
        const codes = blobs[data.values];
        if (!(codes instanceof Uint16Array) || codes.length !== M * N)
            throw new PageError(`a surface's values blob holds ${codes.length} codes, not frames x nodes = ${M * N}`);
        // Frame f's codes are differences from frame f - 1's, mod 65536 (the Uint16Array wraps).
        for (let f = 1, p = N; f < M; f++)
            for (let i = 0; i < N; i++, p++) codes[p] += codes[p - N];
        this.codes = codes;
        this.knots = blobs[data.knots];
        this.K = data.knots_n;
        this.F = data.scale && data.scale.frames > 1 ? data.scale.frames : 1;
        if (this.knots.length !== this.F * 2 * this.K)
            throw new PageError(`a surface's knots blob holds ${this.knots.length} values, not ${this.F} x 2 x ${this.K}`);
        // One scale for the series: t of every code in a table (65536 floats), so a frame is one
        // table look-up per node. A scale per frame: t computed per node.
        this.lut = null;
        if (this.F === 1) {
            const lut = new Float32Array(65536);
            for (let c = 0; c < NAN_CODE; c++) lut[c] = knotT(this.knots, 0, this.K, this.origin + c * this.step);
            lut[NAN_CODE] = NAN_T;
            this.lut = lut;
        }
    }

    value(code) {
        return code === NAN_CODE ? NaN : this.origin + code * this.step;
    }

    // The scale's t of value v at frame f (the colour bar).
    t(v, f = 0) {
        const s = this.F === 1 ? 0 : Math.min(Math.max(f, 0), this.F - 1);
        return knotT(this.knots, s * 2 * this.K, this.K, v);
    }

    // The scale's knot values at frame f (the colour bar's range).
    knotValues(f = 0) {
        const s = this.F === 1 ? 0 : Math.min(Math.max(f, 0), this.F - 1);
        const off = s * 2 * this.K;
        return this.knots.subarray(off, off + this.K);
    }

    // Frame f's t per node into out (a Float32Array of N): no allocation.
    fillT(f, out) {
        const N = this.N, codes = this.codes, base = f * N;
        if (this.lut) {
            const lut = this.lut;
            for (let i = 0; i < N; i++) out[i] = lut[codes[base + i]];
            return;
        }
        const kn = this.knots, K = this.K, off = Math.min(f, this.F - 1) * 2 * K, o = this.origin, st = this.step;
        for (let i = 0; i < N; i++) {
            const c = codes[base + i];
            out[i] = c === NAN_CODE ? NAN_T : knotT(kn, off, K, o + c * st);
        }
    }

    // Node i's decoded values over the M frames.
    nodeSeries(i) {
        const out = new Float64Array(this.M);
        for (let f = 0, p = i; f < this.M; f++, p += this.N) out[f] = this.value(this.codes[p]);
        return out;
    }
}

// The leads: L series of M values (lead-major float32), as subarrays.
export function leadSeries(meta, blobs) {
    const L = meta.leads;
    if (!L) return null;
    const v = blobs[L.values], M = meta.frames;
    if (v.length !== L.names.length * M)
        throw new PageError(`the leads' blob holds ${v.length} values, not ${L.names.length} leads x ${M} frames`);
    return L.names.map((name, k) => ({ name, values: v.subarray(k * M, (k + 1) * M) }));
}
