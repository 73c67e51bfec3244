// Numbers for people: printf's "%.3g" and a time readout.

// v with `digits` significant digits, as printf's %g (no trailing zeros, exponent when far from 1).
export function fmtG(v, digits = 3) {
    if (!Number.isFinite(v)) return Number.isNaN(v) ? 'NaN' : v > 0 ? 'inf' : '-inf';
    if (v === 0) return '0';
    const e = Math.floor(Math.log10(Math.abs(v)));
    if (e < -4 || e >= digits) {
        const [m, x] = v.toExponential(digits - 1).split('e');
        const mm = m.includes('.') ? m.replace(/\.?0+$/, '') : m;
        const xx = Number(x);
        return `${mm}e${xx < 0 ? '-' : '+'}${String(Math.abs(xx)).padStart(2, '0')}`;
    }
    const s = v.toFixed(Math.max(0, digits - 1 - e));
    return s.includes('.') ? s.replace(/\.?0+$/, '') : s;
}

// A time value: whole numbers as they are, others to 4 significant digits.
export function fmtTime(t) {
    if (!Number.isFinite(t)) return String(t);
    return Number.isInteger(t) ? String(t) : fmtG(t, 4);
}
