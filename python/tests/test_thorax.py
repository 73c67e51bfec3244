"""The Python binding against the thorax CLI's own outputs, on the phantom and on the Dalhousie torso.

Run by ctest (python_binding) with THORAX (the CLI), THORAX_LIBRARY (the build's libthorax.so),
PYTHONPATH (python/) and THORAX_DATA (../shared/data) set:
  - models: every surface's nodes and triangles equal the model directory's .pts/.fac read by NumPy;
    the Dalhousie torso's equal map3d's own daltorso.pts/.fac (as triangles, whatever the order);
  - series: raw, text and .mat written by Python read back equal by Python, by `thorax series info`
    and (the .mat) by scipy.io.loadmat; the CLI's beat and map3d's .pot files read equal to NumPy's
    reading of their text;
  - meshing: Model.mesh() gives the very mesh `thorax mesh` writes (same nodes and tetrahedra,
    deterministic), and a model written by Python passes `thorax check`;
  - forward: Model.forward() equals `thorax forward` (its text output) to 1e-9 of the largest value
    on the phantom and on the Dalhousie torso, and obeys the maximum principle (each frame's torso
    potentials within the heart's range: no sources between);
  - errors: the library's messages arrive as ThoraxError naming the file / row / frame.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import thorax

THORAX = os.environ.get("THORAX", "thorax")
DATA = os.environ.get("THORAX_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))
DAL = os.path.join(DATA, "map3d", "geom", "torso")


def run(*args):
    r = subprocess.run([THORAX] + [str(a) for a in args], capture_output=True, text=True)
    if r.returncode != 0:
        raise AssertionError(f"thorax {' '.join(map(str, args))}: exit {r.returncode}: {r.stderr}")
    return r.stdout


def read_ptsfac(pts, fac):
    x = np.loadtxt(pts, ndmin=2)
    f = np.loadtxt(fac, dtype=np.int64, ndmin=2)
    return x, f - (0 if f.min() == 0 else 1)


def read_text_series(path):
    """thorax's text series (docs/formats.md) parsed here, not by the library: header lines
    "key value", then one row of values per line, then "end"."""
    head, rows = {}, []
    with open(path) as f:
        lines = f.readlines()
    for line in lines:
        w = line.split()
        if not w or w[0] == "end":
            continue
        try:
            rows.append([float(x) for x in w])
        except ValueError:
            head[w[0]] = " ".join(w[1:])
    v = np.array(rows)
    assert v.shape == (int(head["rows"]), int(head["frames"])), (path, v.shape, head)
    return v, head


def series_info(path):
    out = {}
    for line in run("series", "info", path).splitlines():
        k, _, v = line.partition(" ")
        out[k] = v.strip()
    return out


def dipole_on(nodes, centre, p):
    """An unbounded-medium dipole's potential at nodes (arbitrary units): p.(x - c) / |x - c|^3."""
    d = nodes - centre
    return d @ p / np.linalg.norm(d, axis=1) ** 3


class Work(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="thorax-python.")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir)

    def path(self, *names):
        return os.path.join(self.dir, *names)


class Phantom(Work):
    """The built-in phantom, made by the CLI (contours, surfaces, mesh, a 4-frame beat, forward)."""

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        d = cls.dir
        run("phantom", "-o", f"{d}/contours.txt", "-q")
        run("surfaces", f"{d}/contours.txt", "-o", f"{d}/model", "-q")
        run("mesh", f"{d}/model", "-o", f"{d}/meshed", "-q")
        # frames at 0, 60, 120, 180, 240 ms: baseline, P wave, PR segment, QRS, ST segment
        run("beat", f"{d}/meshed", "-o", f"{d}/beat.raw", "--frames", 5, "--dt", 60, "-q")
        run("forward", f"{d}/meshed", "--epicardial", f"{d}/beat.raw", "-o", f"{d}/sol", "--format", "text", "-q")

    def test_surfaces_equal_the_files(self):
        m = thorax.Model.read(self.path("model"))
        names = [s.name for s in m.surfaces]
        self.assertEqual(names, ["torso", "fat", "muscle", "lung_r", "lung_l", "heart"])
        for s in m.surfaces:
            x, f = read_ptsfac(self.path("model", s.name + ".pts"), self.path("model", s.name + ".fac"))
            self.assertEqual(s.nodes.shape, x.shape)
            self.assertEqual(s.triangles.dtype, np.int32)
            np.testing.assert_array_equal(s.triangles, f, err_msg=s.name)
            np.testing.assert_allclose(s.nodes, x, rtol=0, atol=5e-7, err_msg=s.name)
        self.assertEqual(m.surface(role="heart").name, "heart")
        self.assertEqual(m.surface("lung_l").role, "lung")
        self.assertIsNone(m.volume)
        self.assertEqual(m.regions, [])

    def test_mesh_is_the_cli_mesh(self):
        m = thorax.Model.read(self.path("model"))
        n_nodes, n_tets = m.mesh()
        cli = thorax.Model.read(self.path("meshed"))
        xyz, tet, reg = m.volume
        cxyz, ctet, creg = cli.volume
        self.assertEqual((n_nodes, n_tets), (len(cxyz), len(ctet)))
        # the CLI's files, read by NumPy: volume.tet is 1-based with a 1-based region column
        vt = np.loadtxt(self.path("meshed", "volume.tet"), dtype=np.int64)
        np.testing.assert_array_equal(tet, vt[:, :4] - 1)
        np.testing.assert_array_equal(reg, vt[:, 4] - 1)
        np.testing.assert_allclose(xyz, np.loadtxt(self.path("meshed", "volume.pts")), rtol=0, atol=5e-7)
        np.testing.assert_array_equal(ctet, tet)
        self.assertEqual([r[0] for r in m.regions], [r[0] for r in cli.regions])
        # every tetrahedron right-handed, their volumes summing to the torso's enclosed volume
        a, b, c, d = (xyz[tet[:, k]] for k in range(4))
        vols = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
        self.assertGreater(vols.min(), 0)
        torso = m.surface(role="outer")
        p, q, r = (torso.nodes[torso.triangles[:, k]] for k in range(3))
        enclosed = np.einsum("ij,ij->i", p, np.cross(q, r)).sum() / 6
        self.assertAlmostEqual(vols.sum() / enclosed, 1.0, places=9)
        # written by Python, checked by the CLI
        m.write(self.path("py_meshed"))
        run("check", self.path("py_meshed"), "-q")

    def test_forward_is_the_cli_forward(self):
        m = thorax.Model.read(self.path("meshed"))
        beat = thorax.read_series(self.path("beat.raw"))
        self.assertEqual(beat.values.shape, (len(m.surface(role="heart").nodes), 5))
        self.assertEqual(beat.unit, "mV")
        np.testing.assert_array_equal(beat.time, [0, 60, 120, 180, 240])
        torso = m.forward(beat)
        cli, head = read_text_series(self.path("sol", "torso.txt"))
        self.assertEqual(torso.values.shape, cli.shape)
        self.assertEqual(head["unit"], "mV")
        scale = np.abs(cli).max()
        self.assertGreater(scale, 0.1)  # a beat, not zeros
        np.testing.assert_allclose(torso.values, cli, rtol=0, atol=1e-9 * scale)
        self.assertEqual(torso.unit, "mV")
        # maximum principle: no sources between the heart and the torso surface (to the iterative
        # solver's tolerance: a frame of zeros on the heart gives some 1e-8 mV on the torso)
        tol = 1e-6 * np.abs(beat.values).max()
        for f in range(5):
            lo, hi = beat.values[:, f].min(), beat.values[:, f].max()
            self.assertTrue(lo - tol <= torso.values[:, f].min() and torso.values[:, f].max() <= hi + tol, f)
        self.assertGreater(np.abs(torso.values[:, 3]).max(), 0.2 * np.abs(beat.values[:, 3]).max())  # QRS reaches the torso
        # a 1-D array in is one frame: the QRS frame alone gives that frame's map (solved from zero,
        # not warm-started from the frame before: equal to the solver's tolerance)
        qrs = m.forward(beat.values[:, 3])
        self.assertEqual(qrs.values.shape, (len(cli), 1))
        np.testing.assert_allclose(qrs.values[:, 0], torso.values[:, 3], rtol=0, atol=1e-6 * scale)

    def test_forward_errors(self):
        m = thorax.Model.read(self.path("meshed"))
        with self.assertRaises(thorax.ThoraxError) as e:
            m.forward(np.zeros((7, 2)))
        self.assertIn("7", str(e.exception))
        bad = np.zeros((len(m.surface(role="heart").nodes), 3))
        bad[5, 2] = np.nan
        with self.assertRaises(thorax.ThoraxError) as e:
            m.forward(bad)
        self.assertIn("row 5 frame 2", str(e.exception))
        unmeshed = thorax.Model.read(self.path("model"))
        with self.assertRaises(thorax.ThoraxError) as e:
            unmeshed.forward(bad[:, :1] * 0)
        self.assertIn("no volume mesh", str(e.exception))


class Series(Work):
    def test_round_trips(self):
        rng = np.random.default_rng(14)
        v = rng.normal(size=(37, 11)) * 3.5
        t = np.arange(11) * 2.0
        for name in ("s.raw", "s.txt", "s.mat"):
            p = self.path(name)
            thorax.write_series(p, v, time=t, unit="mV")
            back = thorax.read_series(p)
            np.testing.assert_array_equal(back.values, v, err_msg=name) if name != "s.txt" else \
                np.testing.assert_allclose(back.values, v, rtol=1e-12, err_msg=name)
            np.testing.assert_allclose(back.time, t, err_msg=name)
            self.assertEqual(back.unit, "mV", name)
            info = series_info(p)
            self.assertEqual((int(info["rows"]), int(info["frames"])), v.shape, name)
            self.assertAlmostEqual(float(info["min"]), v.min(), places=6)
            self.assertAlmostEqual(float(info["max"]), v.max(), places=6)
        import scipy.io
        mat = scipy.io.loadmat(self.path("s.mat"))
        np.testing.assert_array_equal(mat["potvals"], v)

    def test_refusals(self):
        with self.assertRaises(thorax.ThoraxError) as e:
            thorax.read_series(self.path("absent.raw"))
        self.assertIn("absent.raw", str(e.exception))
        with self.assertRaises(thorax.ThoraxError) as e:
            thorax.write_series(self.path("x.raw"), np.array([[1.0, np.inf]]))
        self.assertIn("row 0 frame 1", str(e.exception))
        self.assertFalse(os.path.exists(self.path("x.raw")))
        with self.assertRaises(thorax.ThoraxError):
            thorax.write_series(self.path("x.png"), np.ones((2, 2)))
        with self.assertRaises(thorax.ThoraxError) as e:
            thorax.write_series(self.path("t.raw"), np.ones((2, 2)), time=[0.0, 0.0])
        self.assertFalse(os.path.exists(self.path("t.raw")))


@unittest.skipUnless(os.path.exists(os.path.join(DAL, "daltorso.pts")), "the Dalhousie torso (../shared/data) not found")
class Dalhousie(Work):
    """map3d's Dalhousie torso and epicardium, imported by the CLI."""

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        d = cls.dir
        run("import", "-o", f"{d}/dal", "-q", "--up", "-y", "--front", "-z", f"{DAL}/daltorso.pts", "--name", "torso",
            "--role", "outer", f"{DAL}/dalepi.pts", "--name", "epicardium", "--role", "heart")

    def test_model_is_map3d_files(self):
        m = thorax.Model.read(self.path("dal"))
        for s, stem in ((m.surface(role="outer"), "daltorso"), (m.surface(role="heart"), "dalepi")):
            x, f = read_ptsfac(os.path.join(DAL, stem + ".pts"), os.path.join(DAL, stem + ".fac"))
            np.testing.assert_allclose(s.nodes, x, rtol=0, atol=5e-7, err_msg=stem)
            self.assertEqual({tuple(sorted(t)) for t in s.triangles.tolist()}, {tuple(sorted(t)) for t in f.tolist()})

    def test_pot_files(self):
        torso = thorax.Model.read(self.path("dal")).surface(role="outer")
        maps = [thorax.read_series(os.path.join(DATA, "map3d", "data", "torso", f"dipole2_00{k}.pot")) for k in range(1, 7)]
        for k, s in enumerate(maps, 1):
            p = os.path.join(DATA, "map3d", "data", "torso", f"dipole2_00{k}.pot")
            self.assertEqual(s.values.shape, (len(torso.nodes), 1))
            np.testing.assert_allclose(s.values[:, 0], np.loadtxt(p), rtol=0, atol=1e-12)

    def test_mesh_and_forward_are_the_cli(self):
        m = thorax.Model.read(self.path("dal"))
        m.mesh()
        m.write(self.path("dal_meshed"))
        run("check", self.path("dal_meshed"), "-q")
        heart = m.surface(role="heart")
        centre = heart.nodes.mean(axis=0)
        # two dipoles, and a combination of them: the solution is linear in the heart's potentials
        f1, f2 = dipole_on(heart.nodes, centre, [1, 0, 0]), dipole_on(heart.nodes, centre, [0, 0.6, 0.8])
        frames = np.stack([f1, f2, 0.3 * f1 - 0.5 * f2], axis=1)
        thorax.write_series(self.path("epi.txt"), frames, unit="mV")
        run("forward", self.path("dal_meshed"), "--epicardial", self.path("epi.txt"), "-o", self.path("dsol"),
            "--format", "text", "-q")
        cli, _ = read_text_series(self.path("dsol", "torso.txt"))
        torso = m.forward(frames)
        scale = np.abs(cli).max()
        np.testing.assert_allclose(torso.values, cli, rtol=0, atol=1e-9 * scale)
        tol = 1e-6 * np.abs(frames).max()
        for f in range(3):
            self.assertLessEqual(torso.values[:, f].max(), frames[:, f].max() + tol)
            self.assertGreaterEqual(torso.values[:, f].min(), frames[:, f].min() - tol)
        self.assertEqual(torso.values.shape, (len(m.surface(role="outer").nodes), 3))
        np.testing.assert_allclose(torso.values[:, 2], 0.3 * torso.values[:, 0] - 0.5 * torso.values[:, 1],
                                   rtol=0, atol=1e-6 * scale)

        # the example script on the meshed model: its dipole turns half a turn between frames 0 and 2
        # of 4, so its torso maps there are opposite; its .mat read by scipy
        example = os.path.join(os.path.dirname(__file__), "..", "examples", "dipole_forward.py")
        r = subprocess.run([sys.executable, "-B", example, self.path("dal_meshed"), self.path("ex.mat"), "--frames", "4"],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("wrote", r.stdout)
        import scipy.io
        v = scipy.io.loadmat(self.path("ex.mat"))["potvals"]
        self.assertEqual(v.shape, (len(m.surface(role="outer").nodes), 4))
        self.assertGreater(np.abs(v[:, 0]).max(), 0.01)  # mV: a 0.1 mA m dipole reaches the torso
        np.testing.assert_allclose(v[:, 2], -v[:, 0], rtol=0, atol=1e-6 * np.abs(v).max())


if __name__ == "__main__":
    unittest.main()
