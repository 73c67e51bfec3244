"""thorax for Python: models, time series, meshing and forward solutions over libthorax.so.

NumPy arrays in and out; every failure raises ThoraxError with the library's own message (file,
line, object). Units as everywhere in thorax: millimetres, the series' own unit (mV for the
phantom's beat), indices 0-based.

    import thorax
    m = thorax.Model.read("model")             # a model directory (thorax surfaces / import)
    for s in m.surfaces:                        # Surface: name, role, nodes (n x 3), triangles (t x 3)
        print(s.name, s.nodes.shape, s.triangles.shape)
    m.mesh()                                    # the volume mesh, as `thorax mesh MODEL` makes it
    beat = thorax.read_series("beat.raw")       # Series: values (rows x frames), time, unit
    torso = m.forward(beat)                     # Series: the outer surface's potentials

The library is found as thorax/_lib.py says ($THORAX_LIBRARY, beside the installed package, or the
dynamic linker's path).
"""
import atexit
import ctypes
import os
import weakref

import numpy as np

from ._lib import LIB, SERIES_FORMATS, c_double_p, c_int32_p

# PETSc, started by the first forward solution, is ended once at exit (MPI wants its finalize).
atexit.register(LIB.thx_capi_finalize)

__all__ = ["ThoraxError", "Model", "Surface", "Series", "read_series", "write_series", "version", "library_path"]


class ThoraxError(Exception):
    """A thorax call failed; str() is the library's message, .status the thx_status code."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def version():
    """The library's version ("0.1.0")."""
    return LIB.thx_capi_version().decode()


def library_path():
    """The libthorax.so this package loaded."""
    return LIB.path


class _Ctx:
    """A thx_ctx for one call: the library's message becomes the exception's."""

    def __enter__(self):
        self.p = ctypes.c_void_p()
        if LIB.thx_ctx_create(ctypes.byref(self.p)) != 0:
            raise MemoryError("thorax: no context")
        return self

    def check(self, status):
        if status != 0:
            msg = LIB.thx_ctx_message(self.p).decode(errors="replace")
            kind = LIB.thx_status_name(status).decode()
            raise ThoraxError(status, msg or kind)

    def __exit__(self, *exc):
        LIB.thx_ctx_destroy(ctypes.byref(self.p))
        return False


def _dptr(a):
    return a.ctypes.data_as(c_double_p)


def _iptr(a):
    return a.ctypes.data_as(c_int32_p)


def _path(p):
    return os.fsencode(p)


class Surface:
    """One surface of a model: name, role ("outer", "heart" ...), nodes (n x 3 float64, mm) and
    triangles (t x 3 int32, 0-based, counterclockwise seen from outside). Copies: changing them
    does not change the model."""

    def __init__(self, name, role, nodes, triangles):
        self.name, self.role, self.nodes, self.triangles = name, role, nodes, triangles

    def __repr__(self):
        return f"Surface({self.name!r}, {self.role!r}, {len(self.nodes)} nodes, {len(self.triangles)} triangles)"


def _destroy(destroy, p):
    destroy(ctypes.byref(p))


class Model:
    """A thorax model (surfaces, and a volume mesh once meshed), owned by the library."""

    def __init__(self, handle):
        self._p = handle
        self._fin = weakref.finalize(self, _destroy, LIB.thx_model_destroy, handle)

    @classmethod
    def read(cls, directory):
        """Reads a model directory (model.json, NAME.pts/.fac, the volume if meshed)."""
        p = ctypes.c_void_p()
        with _Ctx() as c:
            c.check(LIB.thx_model_read(c.p, _path(directory), ctypes.byref(p)))
        return cls(p)

    def write(self, directory):
        """Writes the model directory (refuses to replace a directory that is not a thorax model)."""
        with _Ctx() as c:
            c.check(LIB.thx_model_write(c.p, self._p, _path(directory)))

    @property
    def surfaces(self):
        return [self._surface(i) for i in range(LIB.thx_capi_model_n_surfaces(self._p))]

    def surface(self, name=None, role=None):
        """The surface named name, or the first of role role ("outer", "heart" ...)."""
        i = ctypes.c_size_t()
        with _Ctx() as c:
            c.check(LIB.thx_capi_surface_find(c.p, self._p, name.encode() if name else None,
                                              role.encode() if role else None, ctypes.byref(i)))
        return self._surface(i.value)

    def _surface(self, i):
        name, role = ctypes.c_char_p(), ctypes.c_char_p()
        nn, nt = ctypes.c_size_t(), ctypes.c_size_t()
        with _Ctx() as c:
            c.check(LIB.thx_capi_surface_info(c.p, self._p, i, ctypes.byref(name), ctypes.byref(role),
                                              ctypes.byref(nn), ctypes.byref(nt)))
            xyz = np.empty((nn.value, 3), dtype=np.float64)
            tri = np.empty((nt.value, 3), dtype=np.int32)
            c.check(LIB.thx_capi_surface_copy(c.p, self._p, i, _dptr(xyz), _iptr(tri)))
        return Surface(name.value.decode(), role.value.decode(), xyz, tri)

    @property
    def volume(self):
        """(nodes n x 3, tetrahedra t x 4 int32 0-based, region t int32) or None when not meshed."""
        nn, nt, nr = ctypes.c_size_t(), ctypes.c_size_t(), ctypes.c_size_t()
        LIB.thx_capi_volume_info(self._p, ctypes.byref(nn), ctypes.byref(nt), ctypes.byref(nr))
        if nt.value == 0:
            return None
        xyz = np.empty((nn.value, 3), dtype=np.float64)
        tet = np.empty((nt.value, 4), dtype=np.int32)
        reg = np.empty(nt.value, dtype=np.int32)
        with _Ctx() as c:
            c.check(LIB.thx_capi_volume_copy(c.p, self._p, _dptr(xyz), _iptr(tet), _iptr(reg)))
        return xyz, tet, reg

    @property
    def regions(self):
        """[(name, conductivity tensor 3 x 3 in S/m)] of the volume's regions ([] when not meshed)."""
        nr = ctypes.c_size_t()
        LIB.thx_capi_volume_info(self._p, None, None, ctypes.byref(nr))
        out = []
        with _Ctx() as c:
            for r in range(nr.value):
                name, sigma = ctypes.c_char_p(), np.empty(9, dtype=np.float64)
                c.check(LIB.thx_capi_region_info(c.p, self._p, r, ctypes.byref(name), _dptr(sigma)))
                out.append((name.value.decode(), sigma.reshape(3, 3)))
        return out

    def mesh(self, grid=0.0):
        """Meshes the volume in place as `thorax mesh` does (grid spacing in mm, 0 = its default) and
        checks it as thorax check does; returns (nodes, tetrahedra). Write it with write()."""
        nn, nt = ctypes.c_size_t(), ctypes.c_size_t()
        with _Ctx() as c:
            c.check(LIB.thx_capi_mesh(c.p, self._p, float(grid), ctypes.byref(nn), ctypes.byref(nt)))
        return nn.value, nt.value

    def forward(self, heart, unit="mV", time=None):
        """The epicardial forward problem (`thorax forward MODEL --epicardial SERIES`): heart is a
        Series or an array (the heart surface's nodes x frames; a 1-D array is one frame); returns
        the outer surface's potentials as a Series (nodes x frames, the heart's unit)."""
        epi = heart if isinstance(heart, Series) else Series(heart, time=time, unit=unit)
        out = ctypes.c_void_p()
        with _Ctx() as c:
            h = epi._handle(c)
            try:
                c.check(LIB.thx_capi_forward(c.p, self._p, h, ctypes.byref(out)))
            finally:
                LIB.thx_series_destroy(ctypes.byref(h))
        return Series._take(out)


class Series:
    """A time series: values (rows x frames float64: nodes or leads by time instants), time
    (frames, in time_unit, increasing), unit of the values."""

    def __init__(self, values, time=None, unit="", time_unit="ms"):
        v = np.asarray(values, dtype=np.float64)
        if v.ndim == 1:
            v = v[:, None]
        if v.ndim != 2:
            raise ValueError(f"thorax: a series is rows x frames, not an array of shape {v.shape}")
        self.values = v
        self.time = np.arange(v.shape[1], dtype=np.float64) if time is None else np.asarray(time, dtype=np.float64)
        if self.time.shape != (v.shape[1],):
            raise ValueError(f"thorax: {v.shape[1]} frames but {self.time.shape} times")
        self.unit, self.time_unit = unit, time_unit

    def __repr__(self):
        return f"Series({self.values.shape[0]} rows x {self.values.shape[1]} frames, unit {self.unit!r})"

    @classmethod
    def _take(cls, h):
        """A Series copied out of a library thx_series (destroyed here)."""
        try:
            nr, nf = ctypes.c_size_t(), ctypes.c_size_t()
            LIB.thx_capi_series_shape(h, ctypes.byref(nr), ctypes.byref(nf))
            v = np.empty((nr.value, nf.value), dtype=np.float64)
            t = np.empty(nf.value, dtype=np.float64)
            LIB.thx_capi_series_copy(h, _dptr(v), _dptr(t))
            unit = LIB.thx_capi_series_unit(h).decode()
            tunit = LIB.thx_capi_series_time_unit(h).decode()
        finally:
            LIB.thx_series_destroy(ctypes.byref(h))
        return cls(v, t, unit, tunit)

    def _handle(self, c):
        """A library thx_series with these values (the caller destroys it)."""
        v = np.ascontiguousarray(self.values, dtype=np.float64)
        t = np.ascontiguousarray(self.time, dtype=np.float64)
        h = ctypes.c_void_p()
        c.check(LIB.thx_capi_series_from(c.p, v.shape[0], v.shape[1], _dptr(v), _dptr(t), self.unit.encode(),
                                         self.time_unit.encode(), ctypes.byref(h)))
        return h

    def write(self, path, format=None):
        """Writes the series (text .txt/.dat, raw .raw, MATLAB .mat; format overrides the extension)."""
        fmt = ctypes.c_int()
        if LIB.thx_series_output_format(format.encode() if format else None, _path(path), ctypes.byref(fmt)) != 0:
            raise ThoraxError(3, f"{path}: no series format to write ({format or 'by extension'}): "
                                 "text (.txt, .dat), raw (.raw) or mat (.mat)")
        with _Ctx() as c:
            h = self._handle(c)
            try:
                c.check(LIB.thx_series_write(c.p, h, _path(path), fmt.value))
            finally:
                LIB.thx_series_destroy(ctypes.byref(h))


def read_series(path, format="auto"):
    """Reads a series (text, raw, .mat, map3d .pot; format "auto" goes by extension and content)."""
    if format not in SERIES_FORMATS:
        raise ValueError(f"thorax: series format {format!r}: one of {', '.join(SERIES_FORMATS)}")
    h = ctypes.c_void_p()
    with _Ctx() as c:
        c.check(LIB.thx_series_read(c.p, _path(path), SERIES_FORMATS[format], ctypes.byref(h)))
    return Series._take(h)


def write_series(path, series, format=None, **kw):
    """Writes a Series, or an array (rows x frames) with Series' keywords (time, unit, time_unit)."""
    s = series if isinstance(series, Series) else Series(series, **kw)
    s.write(path, format)
