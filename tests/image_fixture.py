"""The synthetic scan and the picture reader of the image e2e tests (tests/image_fixture.sh sources
the shell side; e2e_render_image.sh, e2e_render_image_ct.sh and e2e_view_image.sh use them).

square_image(path, plane=None): a NIfTI written by nibabel, 40 x 40 x 20 voxels of 2 mm, voxel
    centres x, y from -39 to 39 and z from -19 to 19 (faces at +-40 and +-20); value 100, and 1000
    in the square x in -10..10, y in 0..20 (voxel faces) at every z, or only in the plane k = plane
    (z = 2 plane - 19). Returns the volume and its affine.
box(stem='box'): the box around the plane z = 0 (x, y in -30..30, z in -15..15) as map3d
    STEM.pts/STEM.fac, its twelve triangles checked outward.
png(path): a PNG read back with VTK's PNG reader, as rows top to bottom x columns x RGB (ints).
"""
import numpy as np

AFFINE = np.diag([2.0, 2.0, 2.0, 1.0])
AFFINE[:3, 3] = (-39, -39, -19)


def square_image(path, plane=None):
    import nibabel as nib
    v = np.full((40, 40, 20), 100, np.int16)
    v[15:25, 20:30, slice(None) if plane is None else plane] = 1000
    nib.save(nib.Nifti1Image(v, AFFINE), path)
    return v, AFFINE


def box(stem='box'):
    P = np.array([(x, y, z) for z in (-15, 15) for y in (-30, 30) for x in (-30, 30)], float)
    F = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4), (2, 6, 3), (3, 6, 7), (0, 4, 2),
         (2, 4, 6), (1, 3, 5), (3, 7, 5)]
    for a, b, c in F:   # outward: the normal points away from the centre
        n = np.cross(P[b] - P[a], P[c] - P[a])
        assert n @ (P[a] + P[b] + P[c]) > 0, (a, b, c)
    open(stem + '.pts', 'w').write(''.join('%g %g %g\n' % tuple(p) for p in P))
    open(stem + '.fac', 'w').write(''.join('%d %d %d\n' % (a + 1, b + 1, c + 1) for a, b, c in F))


def png(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    r = vtk.vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    im = r.GetOutput()
    w, h, _ = im.GetDimensions()
    assert w > 0 and h > 0, 'not a PNG VTK reads: ' + path
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1][:, :, :3].astype(int)
