// CGAL peer of bench/delaunay.sh (C++, compiled by that script only; not part
// of the project's build): reads a TetGen .node file, builds CGAL's
// Delaunay_triangulation_3 (exact predicates, inexact constructions: the
// kernel CGAL recommends for this) from the whole range, REPEAT times, and
// prints "tets T seconds S" with the best time of the construction alone
// (CGAL's own spatial sort included, like thorax's ordering; reading the
// file and extracting tetrahedra excluded).
//   delaunay_cgal FILE.node [REPEAT]
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_3<K> DT;

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: delaunay_cgal FILE.node [REPEAT]\n");
        return 2;
    }
    int repeat = argc > 2 ? std::atoi(argv[2]) : 1;
    std::FILE *f = std::fopen(argv[1], "r");
    if (!f) { std::perror(argv[1]); return 1; }
    size_t n;
    int dim, na, nb;
    if (std::fscanf(f, "%zu %d %d %d", &n, &dim, &na, &nb) != 4 || dim != 3) { std::fprintf(stderr, "bad header\n"); return 1; }
    std::vector<K::Point_3> pts;
    pts.reserve(n);
    for (size_t i = 0; i < n; i++) {
        size_t id;
        double x, y, z;
        if (std::fscanf(f, "%zu %lf %lf %lf", &id, &x, &y, &z) != 4) { std::fprintf(stderr, "bad line %zu\n", i); return 1; }
        pts.push_back(K::Point_3(x, y, z));
    }
    std::fclose(f);
    double best = 1e30;
    size_t cells = 0;
    for (int r = 0; r < repeat; r++) {
        auto t0 = std::chrono::steady_clock::now();
        DT dt(pts.begin(), pts.end());
        auto t1 = std::chrono::steady_clock::now();
        double s = std::chrono::duration<double>(t1 - t0).count();
        if (s < best) best = s;
        cells = dt.number_of_finite_cells();
    }
    std::printf("tets %zu seconds %.4f\n", cells, best);
    return 0;
}
