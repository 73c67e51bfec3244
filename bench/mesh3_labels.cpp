// The peer of bench/image.sh (issue 25, item 6): CGAL Mesh_3's labeled-image mesher on a NIfTI label
// map. A C++ bench program built by the script with g++ when libcgal-dev is installed, never by the
// project's CMake.
//
//   mesh3_labels LABELS.nii[.gz] OUTDIR [FACET_SIZE FACET_DISTANCE CELL_SIZE [OPTIMIZERS]]
//   (mm; default 4 1 8 timed)
//
// Reads the label map with Debian's libnifti2 (uint8 voxels and an axis-aligned, positive-diagonal
// qform or sform: what bench/torso_labels.py writes; anything else is refused), builds a CGAL::Image_3
// over the same voxels with the same spacing and the same origin (CGAL puts voxel (i, j, k)'s centre
// at (tx + i vx, ty + j vy, tz + k vz), as NIfTI does for a diagonal affine), so both meshers see the
// label map in the same RAS millimetres. Domain:
// Labeled_mesh_domain_3::create_labeled_image_mesh_domain (label 0 is outside; the subdomain index
// is the label; CGAL's default labellized trilinear interpolation of the labels), relative error bound
// 1e-6 of the bounding box. Criteria: facet angle 30 degrees, facet size FACET_SIZE, facet distance
// FACET_DISTANCE, cell radius-edge ratio 3, cell size CELL_SIZE; make_mesh_3's default optimizers (no
// Lloyd, no ODT, sliver perturbation and exudation with their default bounds). OPTIMIZERS `timed`
// (the default: CGAL's own, where each optimizer stops after as long as the refinement took, so the
// mesh depends on the machine's load and differs slightly from run to run) or `untimed` (no time
// limit: the same mesh every run, and slower). Sequential (Debian's
// libcgal-dev without libtbb-dev gives no Parallel_tag). CGAL's default random generator is seeded from
// the clock: the bench reseeds it (seed 0) and gives the domain its own (seed 0), so that `untimed`
// is deterministic (measured: the same .node/.ele bytes in three runs).
//
// Prints (one figure a line, `key value ...`):
//   read S                 seconds to read the file and build the image
//   mesh S                 seconds of domain construction + make_mesh_3 (the figure compared)
//   vertices N / tets N    vertices and cells in the complex
//   dihedral MIN B5 B10    smallest dihedral angle (degrees) over the cells in the complex, and the
//                          counts below 5 and 10 degrees
//   tets_per_label L N ... cells per subdomain (label)
//   interface A B F V      per pair of subdomains (A < B, 0 = outside): facets and distinct vertices
// Writes OUTDIR/cgal.node and cgal.ele (TetGen's layout, 1-based, the label as the element
// attribute; bench/tet_quality.py reads them) and OUTDIR/iface_A_B.pts (the distinct vertices of the
// facets between subdomains A and B, `x y z` in mm; bench/label_distance.py measures them).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>

#include <nifti2_io.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Labeled_mesh_domain_3<K> Mesh_domain;
typedef CGAL::Mesh_triangulation_3<Mesh_domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr> C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Mesh_criteria;
typedef K::Point_3 Point;
namespace params = CGAL::parameters;

static double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Smallest dihedral angle of a tetrahedron, in degrees (the angle between the two faces at each edge).
static double min_dihedral(const std::array<Point, 4> &p)
{
    static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    K::Vector_3 n[4];
    for (int f = 0; f < 4; f++) {
        K::Vector_3 v = CGAL::cross_product(p[fv[f][1]] - p[fv[f][0]], p[fv[f][2]] - p[fv[f][0]]);
        v = v / std::sqrt(v.squared_length());
        if (v * (p[f] - p[fv[f][0]]) > 0) v = -v; // outward: away from the opposite vertex
        n[f] = v;
    }
    double m = 180.0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) {
            double c = std::max(-1.0, std::min(1.0, n[i] * n[j]));
            m = std::min(m, 180.0 - std::acos(c) * 180.0 / M_PI);
        }
    return m;
}

int main(int argc, char **argv)
{
    if ((argc != 3 && argc != 6 && argc != 7) ||
        (argc == 7 && std::strcmp(argv[6], "timed") != 0 && std::strcmp(argv[6], "untimed") != 0)) {
        std::fprintf(stderr, "usage: %s LABELS.nii[.gz] OUTDIR [FACET_SIZE FACET_DISTANCE CELL_SIZE [timed|untimed]]\n",
                     argv[0]);
        return 2;
    }
    const std::string out = argv[2];
    const double facet_size = argc >= 6 ? std::atof(argv[3]) : 4.0;
    const double facet_distance = argc >= 6 ? std::atof(argv[4]) : 1.0;
    const double cell_size = argc >= 6 ? std::atof(argv[5]) : 8.0;
    const bool untimed = argc == 7 && std::strcmp(argv[6], "untimed") == 0;

    auto t0 = std::chrono::steady_clock::now();
    nifti_image *nim = nifti_image_read(argv[1], 1);
    if (!nim) {
        std::fprintf(stderr, "%s: cannot read as NIfTI\n", argv[1]);
        return 1;
    }
    if (nim->datatype != DT_UINT8 || nim->ndim < 3 || (nim->ndim > 3 && nim->nt > 1)) {
        std::fprintf(stderr, "%s: a uint8 3-D label map is needed\n", argv[1]);
        return 1;
    }
    // the affine: sform if set, else qform; it must be diagonal with positive spacing
    double A[3][4];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            A[r][c] = nim->sform_code > 0 ? nim->sto_xyz.m[r][c] : nim->qto_xyz.m[r][c];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            if ((r == c && !(A[r][c] > 0)) || (r != c && std::fabs(A[r][c]) > 1e-9)) {
                std::fprintf(stderr, "%s: the affine must be diagonal with positive spacing (row %d column %d is %g)\n",
                             argv[1], r, c, A[r][c]);
                return 1;
            }
    const size_t nx = nim->nx, ny = nim->ny, nz = nim->nz;
    _image *im = ::_createImage(nx, ny, nz, 1, A[0][0], A[1][1], A[2][2], 1, WK_FIXED, SGN_UNSIGNED);
    std::memcpy(im->data, nim->data, nx * ny * nz); // both i fastest, then j, then k
    im->tx = float(A[0][3]);
    im->ty = float(A[1][3]);
    im->tz = float(A[2][3]);
    nifti_image_free(nim);
    CGAL::Image_3 image(im);
    std::printf("read %.3f\n", seconds_since(t0));
    std::printf("image %zu %zu %zu spacing %g %g %g origin %g %g %g\n", nx, ny, nz, image.vx(), image.vy(),
                image.vz(), double(im->tx), double(im->ty), double(im->tz));
    std::printf("criteria facet_angle 30 facet_size %g facet_distance %g cell_radius_edge_ratio 3 cell_size %g "
                "optimizers %s\n", facet_size, facet_distance, cell_size, untimed ? "untimed" : "timed");
    std::fflush(stdout);

    t0 = std::chrono::steady_clock::now();
    CGAL::get_default_random() = CGAL::Random(0);
    CGAL::Random rng(0);
    Mesh_domain domain = Mesh_domain::create_labeled_image_mesh_domain(image, params::relative_error_bound = 1e-6,
                                                                       params::p_rng = &rng);
    Mesh_criteria criteria(params::facet_angle = 30, params::facet_size = facet_size,
                           params::facet_distance = facet_distance, params::cell_radius_edge_ratio = 3,
                           params::cell_size = cell_size);
    // untimed: time limit 0 (none) for the optimizers, instead of CGAL's default (the refinement's time)
    C3t3 c3t3 = untimed ? CGAL::make_mesh_3<C3t3>(domain, criteria, params::perturb(params::time_limit = 0),
                                                  params::exude(params::time_limit = 0))
                        : CGAL::make_mesh_3<C3t3>(domain, criteria);
    std::printf("mesh %.3f\n", seconds_since(t0));

    // vertices of the cells in the complex, numbered from 1
    const Tr &tr = c3t3.triangulation();
    std::map<Tr::Vertex_handle, size_t> vid;
    std::vector<Point> pts;
    auto pt = [&](Tr::Vertex_handle v) { return tr.geom_traits().construct_point_3_object()(tr.point(v)); };
    for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c)
        for (int i = 0; i < 4; i++)
            if (vid.emplace(c->vertex(i), pts.size() + 1).second) pts.push_back(pt(c->vertex(i)));
    std::printf("vertices %zu\ntets %zu\n", pts.size(), size_t(c3t3.number_of_cells_in_complex()));

    std::ofstream node(out + "/cgal.node"), ele(out + "/cgal.ele");
    node << pts.size() << " 3 0 0\n";
    node.precision(17);
    for (size_t i = 0; i < pts.size(); i++)
        node << i + 1 << ' ' << pts[i].x() << ' ' << pts[i].y() << ' ' << pts[i].z() << '\n';
    ele << c3t3.number_of_cells_in_complex() << " 4 1\n";
    double dmin = 180.0;
    size_t b5 = 0, b10 = 0, n = 0;
    std::map<int, size_t> per_label;
    for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
        std::array<Point, 4> p;
        std::array<size_t, 4> v;
        for (int i = 0; i < 4; i++) {
            v[i] = vid[c->vertex(i)];
            p[i] = pts[v[i] - 1];
        }
        if (CGAL::orientation(p[0], p[1], p[2], p[3]) == CGAL::NEGATIVE) { // right-handed, as thorax writes
            std::swap(v[2], v[3]);
            std::swap(p[2], p[3]);
        }
        double d = min_dihedral(p);
        dmin = std::min(dmin, d);
        b5 += d < 5;
        b10 += d < 10;
        int lab = int(c3t3.subdomain_index(c));
        per_label[lab]++;
        ele << ++n << ' ' << v[0] << ' ' << v[1] << ' ' << v[2] << ' ' << v[3] << ' ' << lab << '\n';
    }
    std::printf("dihedral %.3f %zu %zu\n", dmin, b5, b10);
    std::printf("tets_per_label");
    for (auto &kv : per_label) std::printf(" %d %zu", kv.first, kv.second);
    std::printf("\n");

    // facets between two subdomains (0: outside the complex), their distinct vertices per pair
    std::map<std::pair<int, int>, std::pair<size_t, std::map<Tr::Vertex_handle, Point>>> iface;
    for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
        Tr::Cell_handle c = f->first;
        Tr::Facet m = tr.mirror_facet(*f);
        int a = c3t3.is_in_complex(c) ? int(c3t3.subdomain_index(c)) : 0;
        int b = c3t3.is_in_complex(m.first) ? int(c3t3.subdomain_index(m.first)) : 0;
        if (a == b) continue;
        auto &e = iface[std::make_pair(std::min(a, b), std::max(a, b))];
        e.first++;
        for (int i = 0; i < 4; i++)
            if (i != f->second) e.second.emplace(c->vertex(i), pt(c->vertex(i)));
    }
    for (auto &kv : iface) {
        std::printf("interface %d %d %zu %zu\n", kv.first.first, kv.first.second, kv.second.first,
                    kv.second.second.size());
        char name[64];
        std::snprintf(name, sizeof name, "/iface_%d_%d.pts", kv.first.first, kv.first.second);
        std::ofstream o(out + name);
        o.precision(9);
        for (auto &vp : kv.second.second) o << vp.second.x() << ' ' << vp.second.y() << ' ' << vp.second.z() << '\n';
    }
    return node && ele ? 0 : 1;
}
