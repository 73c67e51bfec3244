"""Loading libthorax.so and declaring the C functions the binding calls (ctypes).

Only opaque pointers, sizes, strings and caller-allocated arrays cross the boundary: the flat
accessors of thorax/capi/capi.h and the library's own flat calls (thx_model_read, thx_series_read
...). No struct layout is mirrored here, so a change in the library's structs cannot silently break
the binding.

Where the library is looked for, first found wins:
  1. $THORAX_LIBRARY (a path to libthorax.so*; the build tree's tests set it);
  2. beside the installed package (_installed.py, written by `make install`: a path relative to
     this directory, so that a staged or moved prefix still works);
  3. the dynamic linker's search (ctypes.util.find_library("thorax"), then "libthorax.so").
"""
import ctypes
import ctypes.util
import os

c_int32_p = ctypes.POINTER(ctypes.c_int32)
c_double_p = ctypes.POINTER(ctypes.c_double)
c_size_t_p = ctypes.POINTER(ctypes.c_size_t)
c_char_pp = ctypes.POINTER(ctypes.c_char_p)
c_void_pp = ctypes.POINTER(ctypes.c_void_p)

# thx_series_format (thorax/io/series_file.h)
SERIES_FORMATS = {"auto": 0, "text": 1, "raw": 2, "mat": 3, "pot": 4}

# name: (restype, argtypes)
_PROTOTYPES = {
    "thx_ctx_create": (ctypes.c_int, [c_void_pp]),
    "thx_ctx_destroy": (None, [c_void_pp]),
    "thx_ctx_message": (ctypes.c_char_p, [ctypes.c_void_p]),
    "thx_status_name": (ctypes.c_char_p, [ctypes.c_int]),
    "thx_capi_version": (ctypes.c_char_p, []),
    # models
    "thx_model_read": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_char_p, c_void_pp]),
    "thx_model_write": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p]),
    "thx_model_destroy": (None, [c_void_pp]),
    "thx_capi_model_n_surfaces": (ctypes.c_size_t, [ctypes.c_void_p]),
    "thx_capi_surface_info": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, c_char_pp, c_char_pp,
                                             c_size_t_p, c_size_t_p]),
    "thx_capi_surface_copy": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, c_double_p, c_int32_p]),
    "thx_capi_surface_find": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p,
                                             c_size_t_p]),
    "thx_capi_volume_info": (None, [ctypes.c_void_p, c_size_t_p, c_size_t_p, c_size_t_p]),
    "thx_capi_volume_copy": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, c_double_p, c_int32_p, c_int32_p]),
    "thx_capi_region_info": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, c_char_pp, c_double_p]),
    # series
    "thx_series_read": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, c_void_pp]),
    "thx_series_write": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]),
    "thx_series_output_format": (ctypes.c_int, [ctypes.c_char_p, ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]),
    "thx_series_destroy": (None, [c_void_pp]),
    "thx_capi_series_shape": (None, [ctypes.c_void_p, c_size_t_p, c_size_t_p]),
    "thx_capi_series_unit": (ctypes.c_char_p, [ctypes.c_void_p]),
    "thx_capi_series_time_unit": (ctypes.c_char_p, [ctypes.c_void_p]),
    "thx_capi_series_copy": (None, [ctypes.c_void_p, c_double_p, c_double_p]),
    "thx_capi_series_from": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t, c_double_p, c_double_p,
                                            ctypes.c_char_p, ctypes.c_char_p, c_void_pp]),
    # meshing, forward solutions
    "thx_capi_mesh": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, c_size_t_p, c_size_t_p]),
    "thx_capi_forward": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, c_void_pp]),
    "thx_capi_finalize": (None, []),
}


def _candidates():
    env = os.environ.get("THORAX_LIBRARY")
    if env:
        yield env
        return  # asked for this one: no silent fallback to another
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        from . import _installed
        yield os.path.normpath(os.path.join(here, _installed.LIBRARY))
    except ImportError:
        pass
    found = ctypes.util.find_library("thorax")
    if found:
        yield found
    yield "libthorax.so"


def load():
    errors = []
    for path in _candidates():
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            errors.append(f"{path}: {e}")
            continue
        for name, (res, args) in _PROTOTYPES.items():
            fn = getattr(lib, name)  # AttributeError names a library too old for this binding
            fn.restype = res
            fn.argtypes = args
        lib.path = path
        return lib
    raise OSError("thorax: libthorax.so not found (set THORAX_LIBRARY to its path): " + "; ".join(errors))


LIB = load()
