#!/usr/bin/env python3
"""A torso-shaped label map for bench/image.sh (issue 25, item 6): five tissues in a CT-sized volume,
written as NIfTI-1 (.nii or .nii.gz) through nibabel. Deterministic (no random numbers; the same
bytes for the same arguments).

Usage: torso_labels.py [--closed] OUT.nii[.gz] [NX NY NZ]       (default 512 512 300)

The volume covers the same body at any size: 409.6 x 409.6 x 300 mm (a CT's 0.8 x 0.8 x 1.0 mm
voxels at 512 x 512 x 300; other sizes scale the spacing). Frame: RAS mm (+x the subject's right,
+y anterior, +z superior); index axes i, j, k along +x, +y, +z; voxel (0, 0, 0)'s centre at
(-204.4, -204.4, 0.5) at the default size (the x-y centre of the volume is x = y = 0).

Values (uint8):
  0  air (outside the body)
  1  fat: the subcutaneous layer, 6-22 mm under the skin (thicker at the sides and the back)
  2  muscle / lean soft tissue: everything inside the fat layer that is not lung or heart
     (chest-wall muscle, mediastinum, spine region, and below the diaphragm the abdomen)
  3  lung: two lungs (right larger; the left with a cardiac notch), domes on the diaphragm,
     apices near the top, each wrapped around the spine behind and kept about 6 mm off the heart
  4  heart: the myocardium, a tilted ellipsoidal shell (long axis toward left, anterior, inferior)
  5  blood: the two ventricular pools inside it (the right a crescent beside the left)
The body is a superellipse in every plane, wider toward the shoulders; no tissue touches the
volume's border. By default the body is cut flat 6 mm inside both ends of the volume, as a scan's
field of view cuts a torso: fat and muscle reach the cut, so air, fat and muscle meet along its
edges (interfaces 0|1, 0|2, 1|2, 2|3, 2|4, 4|5). --closed rounds both ends instead (the skin's
cross-section shrinks as a superellipse of exponent 6 to nothing at 6 mm from the ends, the fat
layer 14 mm further in), so every tissue is enclosed by the next (interfaces 0|1, 1|2, 2|3, 2|4,
4|5): nested closed surfaces."""
import sys
import numpy as np
import nibabel as nib

FOV = (409.6, 409.6, 300.0)  # mm covered by the volume, whatever its voxel count


def rotation():
    """Heart axes: long axis u toward left (-x), anterior (+y), inferior (-z); then v, w."""
    u = np.array([-0.55, 0.45, -0.70])
    u /= np.linalg.norm(u)
    v = np.cross(u, [0.0, 0.0, 1.0])
    v /= np.linalg.norm(v)
    w = np.cross(u, v)
    return np.stack([u, v, w])  # rows: the heart's axes in RAS


HEART_C = np.array([-22.0, 35.0, 150.0])   # centre of the heart (mm)
HEART_AX = np.array([62.0, 46.0, 44.0])    # outer semi-axes along u, v, w
LV_C = np.array([8.0, -6.0, 0.0])          # left-ventricular pool, in heart axes
LV_AX = np.array([42.0, 20.0, 22.0])
RV_C = np.array([4.0, 26.0, 8.0])          # right-ventricular pool, in heart axes
RV_AX = np.array([38.0, 16.0, 28.0])


def ellipsoid(q, c, ax):
    return (((q - c) / ax) ** 2).sum(axis=-1)


def body_radius(theta, t):
    """The skin: a superellipse (exponent 2.6) whose half-width grows toward the shoulders,
    flattened at the back, with a shallow groove along the spine; t = z / 300 mm."""
    a = 150.0 + 20.0 * np.clip((t - 0.55) / 0.45, 0, 1) ** 1.5 + 6.0 * np.sin(np.pi * t)
    b = 112.0 - 8.0 * t
    p = 2.6
    c, s = np.cos(theta), np.sin(theta)
    r = (np.abs(c / a) ** p + np.abs(s / b) ** p) ** (-1.0 / p)
    back = s < 0
    r = np.where(back, r * (1.0 - 0.06 * np.abs(s) ** 3), r)
    groove = 6.0 * np.exp(-((theta + np.pi / 2) / 0.08) ** 2)
    return r - groove


def fat_depth(theta, t):
    """Subcutaneous fat thickness (mm): 6 anteriorly, up to 22 at the flanks and back."""
    c, s = np.cos(theta), np.sin(theta)
    return 6.0 + 10.0 * c * c + 6.0 * np.clip(-s, 0, 1) + 3.0 * np.sin(2.0 * np.pi * t) ** 2


def end_scale(z, margin):
    """1 in the middle, falling to 0 at `margin` mm from either end (a superellipse of exponent 6)."""
    h = FOV[2] / 2.0 - margin
    u = min(abs(z - FOV[2] / 2.0) / h, 1.0)
    return (1.0 - u ** 6) ** (1.0 / 6.0)


def make(n, closed=False):
    sp = np.array(FOV) / np.array(n)
    origin = np.array([-(n[0] - 1) / 2.0 * sp[0], -(n[1] - 1) / 2.0 * sp[1], sp[2] / 2.0])
    x = origin[0] + sp[0] * np.arange(n[0])
    y = origin[1] + sp[1] * np.arange(n[1])
    X, Y = np.meshgrid(x, y, indexing="ij")   # (i, j) -> x, y
    r = np.hypot(X, Y)
    theta = np.arctan2(Y, X)
    Rm = rotation()
    out = np.zeros(tuple(n), dtype=np.uint8)
    for k in range(n[2]):
        z = origin[2] + sp[2] * k
        t = z / FOV[2]
        lab = np.zeros((n[0], n[1]), dtype=np.uint8)
        if z < 6.0 or z > FOV[2] - 6.0:      # nothing on the first and last 6 mm: no tissue at the border
            out[:, :, k] = lab
            continue
        R = body_radius(theta, t)
        if closed:
            inside = r < R * end_scale(z, 6.0)
            lean = r < (R - fat_depth(theta, t)) * end_scale(z, 20.0)
        else:
            inside = r < R
            lean = r < R - fat_depth(theta, t)
        lab[inside] = 1
        lab[lean] = 2
        # heart, in its own axes
        P = np.stack([X - HEART_C[0], Y - HEART_C[1], np.full_like(X, z - HEART_C[2])], axis=-1)
        Q = P @ Rm.T
        heart = ellipsoid(Q, 0.0, HEART_AX) < 1.0
        keep_off = ellipsoid(Q, 0.0, HEART_AX + 6.0) < 1.0
        lv = ellipsoid(Q, LV_C, LV_AX) < 1.0
        rv = (ellipsoid(Q, RV_C, RV_AX) < 1.0) & ~(ellipsoid(Q, LV_C, LV_AX + 9.0) < 1.0)
        inner_wall = ellipsoid(Q, 0.0, HEART_AX - 7.0) < 1.0
        # lungs: superellipsoids on a domed diaphragm, apex at ~275 mm, away from spine and heart
        lungs = np.zeros_like(inside)
        for side, cx, ax, dome in ((+1, 78.0, 62.0, 118.0), (-1, -80.0, 56.0, 128.0)):
            cy = -5.0
            h = np.clip((275.0 - z) / 150.0, 0, None)            # 0 at the apex, 1 at 125 mm
            width = np.sqrt(np.clip(1.0 - (1.0 - h) ** 2, 0, 1)) if h < 1 else 1.0
            a, b = ax * max(width, 1e-3), 95.0 * max(width, 1e-3)
            body = (np.abs((X - cx) / a) ** 2.4 + np.abs((Y - cy) / b) ** 2.4) < 1.0
            diaphragm = dome - 30.0 * ((X - cx) / 70.0) ** 2 - 20.0 * ((Y - cy) / 90.0) ** 2
            lung = body & (z > diaphragm) & (side * X > 18.0)
            spine = np.hypot(X, Y + 78.0) < 34.0
            lung &= ~spine & ~keep_off & (r < R - fat_depth(theta, t) - 14.0)
            lungs |= lung
        lab[lungs & lean] = 3
        lab[heart & lean] = 4
        lab[(lv | rv) & inner_wall & lean] = 5
        out[:, :, k] = lab
    aff = np.diag([sp[0], sp[1], sp[2], 1.0])
    aff[:3, 3] = origin
    return out, aff


def main():
    args = sys.argv[1:]
    closed = bool(args) and args[0] == "--closed"
    if closed:
        args = args[1:]
    if len(args) not in (1, 4):
        sys.exit(__doc__)
    n = (512, 512, 300) if len(args) == 1 else tuple(int(a) for a in args[1:4])
    lab, aff = make(n, closed)
    img = nib.Nifti1Image(lab, aff)
    img.header.set_xyzt_units("mm")
    img.header.set_qform(aff, code=1)
    img.header.set_sform(aff, code=1)
    img.header["descrip"] = b"bench/torso_labels.py"
    nib.save(img, args[0])
    counts = np.bincount(lab.ravel(), minlength=6)
    print("%s: %d x %d x %d, spacing %.3f %.3f %.3f mm, voxels per label 0-5: %s" %
          (args[0], n[0], n[1], n[2], aff[0, 0], aff[1, 1], aff[2, 2], " ".join(str(c) for c in counts)))


if __name__ == "__main__":
    main()
