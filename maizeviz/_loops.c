/* Compiled loops for maizeviz that numpy runs as dozens of passes over temporaries: the
 * triangle areas of K = 4 reference grids (what a triangle budget widens its leaves to), the
 * distances of a splitting's data points from its chords, and the B-spline basis matrices
 * every surface is fitted and sampled with.
 *
 * Each function computes, element by element, exactly the floating-point operations the numpy
 * code it stands for (maizeviz/mesh/measures.py _grid_areas, maizeviz/mesh/simplify.py
 * _segment_distance) performs, in the same order, and leaves every sum whose order numpy
 * chooses (pairwise summation) to numpy: the results are numpy's to the bit, which
 * tests/core/test_loops.py checks. Built with -ffp-contract=off (MSVC /fp:precise) so
 * that no multiply and add fuse into one rounding, as numpy's separate calls never do.
 *
 * Built when maizeviz is installed, as the extension module maizeviz._loops (setup.py),
 * with Python's stable ABI; maizeviz/loops.py calls the mz_* functions below through
 * ctypes (which releases the GIL, so threads mesh chunks in parallel). The module itself only
 * tells its source's hash.
 */

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <stdint.h>
#include <stdlib.h>
#include <math.h>

#if defined(_MSC_VER)
#define MZ_EXPORT __declspec(dllexport)
#define restrict __restrict
#else
#define MZ_EXPORT __attribute__((visibility("default")))
#endif

/* One row of quads (n of them) of mz_grid_twice_areas: the edges along the row (h0) and the
 * next (h1s: squared lengths), across it at each quad's two columns (w0, and w1s squared), the
 * diagonals (e); distinct arrays (restrict), so that the loop runs in SIMD lanes unchecked. */
static void quad_row(int64_t n, double tol, const double *restrict h0x,
                     const double *restrict h0y, const double *restrict h0z,
                     const double *restrict h0s, const double *restrict h1s,
                     const double *restrict w0x, const double *restrict w0y,
                     const double *restrict w0z, const double *restrict w0s,
                     const double *restrict w1s, const double *restrict ex,
                     const double *restrict ey, const double *restrict ez,
                     double *restrict o0, double *restrict o1) {
    for (int64_t j = 0; j < n; ++j) {
        /* (p00, p10, p11): w0 x d; (p00, p11, p01): d x h0; each term p q - r s */
        double c0 = w0y[j] * ez[j], c1 = w0z[j] * ex[j], c2 = w0x[j] * ey[j];
        c0 -= w0z[j] * ey[j];
        c1 -= w0x[j] * ez[j];
        c2 -= w0y[j] * ex[j];
        double s0 = c0 * c0;
        s0 += c1 * c1;
        s0 += c2 * c2;
        double k0 = ey[j] * h0z[j], k1 = ez[j] * h0x[j], k2 = ex[j] * h0y[j];
        k0 -= ez[j] * h0y[j];
        k1 -= ex[j] * h0z[j];
        k2 -= ey[j] * h0x[j];
        double s1 = k0 * k0;
        s1 += k1 * k1;
        s1 += k2 * k2;
        s0 = sqrt(s0);
        s1 = sqrt(s1);
        const int bad0 = (h1s[j] <= tol) | (w0s[j] <= tol);
        const int bad1 = (h0s[j] <= tol) | (w1s[j] <= tol);
        o0[j] = bad0 ? 0.0 : s0;
        o1[j] = bad1 ? 0.0 : s1;
    }
}

/* For nl vertex grids (nl, a, b, 3) float64, C order: twice the area of each grid triangle,
 * (p00, p10, p11) into first (nl, a - 1, b - 1) and (p00, p11, p01) into second, 0 where a
 * grid edge of the triangle is no longer than rel_tol2 x the grid's longest squared edge
 * (what _grid_areas leaves out). Each grid's edges and diagonals are computed once, into
 * scratch arrays one coordinate apart, so that the triangles' loop runs in SIMD lanes.
 * Returns 0, -2 for a grid under 2 x 2 or a negative count (nothing written), or -3 out of
 * memory. */
MZ_EXPORT int mz_grid_twice_areas(const double *vertices, int64_t nl, int64_t a, int64_t b,
                                  double rel_tol2, double *first, double *second) {
    if (nl < 0 || a < 2 || b < 2) return -2;
    const int64_t row = 3 * b, grid = a * row, q = (a - 1) * (b - 1), c = b - 1;
    const int64_t nh = a * c, nw = (a - 1) * b;
    double *buf = malloc(sizeof(double) * (size_t)(4 * nh + 4 * nw + 3 * q));
    if (buf == NULL) return -3;
    double *hx = buf, *hy = hx + nh, *hz = hy + nh, *hs = hz + nh;     /* along rows */
    double *wx = hs + nh, *wy = wx + nw, *wz = wy + nw, *ws = wz + nw;  /* across rows */
    double *dx = ws + nw, *dy = dx + q, *dz = dy + q;                   /* p11 - p00 */
    for (int64_t l = 0; l < nl; ++l) {
        const double *v = vertices + l * grid;
        for (int64_t i = 0; i < a; ++i)                 /* p(i, j + 1) - p(i, j) */
            for (int64_t j = 0; j < c; ++j) {
                const double *p = v + i * row + 3 * j;
                hx[i * c + j] = p[3] - p[0];
                hy[i * c + j] = p[4] - p[1];
                hz[i * c + j] = p[5] - p[2];
            }
        for (int64_t i = 0; i + 1 < a; ++i)             /* p(i + 1, j) - p(i, j) */
            for (int64_t j = 0; j < b; ++j) {
                const double *p = v + i * row + 3 * j;
                wx[i * b + j] = p[row] - p[0];
                wy[i * b + j] = p[row + 1] - p[1];
                wz[i * b + j] = p[row + 2] - p[2];
            }
        for (int64_t i = 0; i + 1 < a; ++i)
            for (int64_t j = 0; j < c; ++j) {
                const double *p = v + i * row + 3 * j;
                dx[i * c + j] = p[row + 3] - p[0];
                dy[i * c + j] = p[row + 4] - p[1];
                dz[i * c + j] = p[row + 5] - p[2];
            }
        for (int64_t k = 0; k < nh; ++k) {
            double s = hx[k] * hx[k];
            s += hy[k] * hy[k];
            s += hz[k] * hz[k];
            hs[k] = s;
        }
        for (int64_t k = 0; k < nw; ++k) {
            double s = wx[k] * wx[k];
            s += wy[k] * wy[k];
            s += wz[k] * wz[k];
            ws[k] = s;
        }
        double hmax = 0.0, wmax = 0.0;
        int nan = 0;
        for (int64_t k = 0; k < nh; ++k) {
            nan |= hs[k] != hs[k];
            hmax = hs[k] > hmax ? hs[k] : hmax;
        }
        for (int64_t k = 0; k < nw; ++k) {
            nan |= ws[k] != ws[k];
            wmax = ws[k] > wmax ? ws[k] : wmax;
        }
        /* np.maximum of the two maxima (each NaN if any of its values is), then of 1e-300 */
        double longest = nan ? NAN : (hmax > wmax ? hmax : wmax);
        if (!nan && !(longest >= 1e-300)) longest = 1e-300;
        const double tol = rel_tol2 * longest;
        double *t0 = first + l * q, *t1 = second + l * q;
        for (int64_t i = 0; i + 1 < a; ++i)
            quad_row(c, tol, hx + i * c, hy + i * c, hz + i * c, hs + i * c, hs + (i + 1) * c,
                     wx + i * b, wy + i * b, wz + i * b, ws + i * b, ws + i * b + 1,
                     dx + i * c, dy + i * c, dz + i * c, t0 + i * c, t1 + i * c);
    }
    free(buf);
    return 0;
}

/* Distances d[j] of the n points p from the chords a-b, point by point, each coordinate's
 * array apart (x, y, z at offsets p, a, b of the grids' arrays); distinct arrays (restrict),
 * so that the loop runs in SIMD lanes. */
static void chord_distances(int64_t n, const double *restrict x, const double *restrict y,
                            const double *restrict z, int64_t p, int64_t a, int64_t b,
                            double *restrict d) {
    for (int64_t j = 0; j < n; ++j) {
        const double abx = x[b + j] - x[a + j], aby = y[b + j] - y[a + j],
                     abz = z[b + j] - z[a + j];
        const double apx = x[p + j] - x[a + j], apy = y[p + j] - y[a + j],
                     apz = z[p + j] - z[a + j];
        double denom = abx * abx;
        denom += aby * aby;
        denom += abz * abz;
        double dot = apx * abx;
        dot += apy * aby;
        dot += apz * abz;
        double t = dot / (denom > 0 ? denom : 1.0);
        /* np.maximum(t, 0), np.minimum(., 1): NaN stays NaN (the sign of a zero returned may
         * differ from numpy's, which no result can show: t only scales an edge whose product
         * is subtracted and squared) */
        t = (t >= 0.0) | (t != t) ? t : 0.0;
        t = (t <= 1.0) | (t != t) ? t : 1.0;
        const double dx = apx - t * abx, dy = apy - t * aby, dz = apz - t * abz;
        double d2 = dx * dx;
        d2 += dy * dy;
        d2 += dz * dz;
        d[j] = sqrt(d2);
    }
}

/* For R lines of nl grids whose x, y, z are three (nl, m, n) float64 arrays (C order): the
 * largest distance of line[r]'s n points of grid leaf[r] from the chords joining, point by
 * point, lines lo[r] and hi[r] of that grid, as simplify.py's _segment_distance(...).max()
 * computes it (a NaN if any distance is). Returns 0, -2 for an index outside the grids or
 * n < 1 (nothing written), or -3 out of memory. */
MZ_EXPORT int mz_chord_errors(const double *x, const double *y, const double *z, int64_t nl,
                              int64_t m, int64_t n, int64_t r_count, const int64_t *leaf,
                              const int64_t *line, const int64_t *lo, const int64_t *hi,
                              double *out) {
    if (n < 1 || m < 0 || nl < 0 || r_count < 0) return -2;
    for (int64_t r = 0; r < r_count; ++r)     /* every index first: all or nothing written */
        if (leaf[r] < 0 || leaf[r] >= nl || line[r] < 0 || line[r] >= m || lo[r] < 0
                || lo[r] >= m || hi[r] < 0 || hi[r] >= m)
            return -2;
    double *d = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    if (d == NULL) return -3;
    for (int64_t r = 0; r < r_count; ++r) {
        const int64_t g = leaf[r] * m * n;
        chord_distances(n, x, y, z, g + line[r] * n, g + lo[r] * n, g + hi[r] * n, d);
        double best = 0.0, nan_value = 0.0;
        int nan = 0;
        for (int64_t j = 0; j < n; ++j) {
            if (d[j] != d[j]) {
                if (!nan) nan_value = d[j];
                nan = 1;
            } else if (j == 0 || d[j] > best) {
                best = d[j];
            }
        }
        out[r] = nan ? nan_value : best;
    }
    free(d);
    return 0;
}

/* Dense B-spline basis matrices (The NURBS Book A2.2), as maizeviz/leaf/nurbs.py's
 * basis_matrix computes them with numpy: for nl rows of points x (nl, na) and clamped knots
 * (nl, nk), out (nl, na, nk - degree - 1) zero but for each point's degree + 1 values. The
 * span is the count of knots at most x, less one, kept within degree .. n_control - 1; the
 * values come from the same divisions, products and sums in the same order (a first sum
 * 0.0 + y included, which turns -0.0 into 0.0 as numpy's does). degree <= 15. Returns 0, -1
 * for a degree past 15, or -2 for fewer than 2 (degree + 1) knots a row (a clamped vector
 * needs degree + 1 at each end: with fewer, the span's knots k[span - degree + 1 ..
 * span + degree] reach outside the row), nothing written. */
MZ_EXPORT int mz_basis_matrix(const double *x, const double *knots, int64_t nl, int64_t na,
                              int64_t nk, int64_t degree, double *out) {
    if (degree > 15 || degree < 0) return -1;
    if (nk < 2 * (degree + 1) || nl < 0 || na < 0) return -2;
    const int64_t nctrl = nk - degree - 1;
    for (int64_t l = 0; l < nl; ++l) {
        const double *k = knots + l * nk;
        for (int64_t i = 0; i < na; ++i) {
            const double t = x[l * na + i];
            int64_t span = -1;
            for (int64_t q = 0; q < nk; ++q) span += t >= k[q];
            if (span < degree) span = degree;
            if (span > nctrl - 1) span = nctrl - 1;
            double left[16], right[16], vals[16], next[16];
            for (int64_t j = 1; j <= degree; ++j) {
                left[j] = t - k[span + 1 - j];
                right[j] = k[span + j] - t;
            }
            vals[0] = 1.0;
            for (int64_t j = 1; j <= degree; ++j) {
                double saved = 0.0;
                for (int64_t r = 0; r < j; ++r) {
                    const double temp = vals[r] / (right[r + 1] + left[j - r]);
                    next[r] = saved + right[r + 1] * temp;
                    saved = left[j - r] * temp;
                }
                next[j] = saved;
                for (int64_t r = 0; r <= j; ++r) vals[r] = next[r];
            }
            double *row = out + (l * na + i) * nctrl;
            for (int64_t c = 0; c < nctrl; ++c) row[c] = 0.0;
            for (int64_t r = 0; r <= degree; ++r) row[span - degree + r] = vals[r];
        }
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* The Python module: its source's hash (setup.py passes it as MZ_SOURCE_SHA256), so that the
 * loader can tell a module built from another _loops.c. */

#ifndef MZ_SOURCE_SHA256
#define MZ_SOURCE_SHA256 unknown
#endif
#define MZ_STR2(x) #x
#define MZ_STR(x) MZ_STR2(x)

static struct PyModuleDef mz_module = {
    PyModuleDef_HEAD_INIT, "_loops",
    "Compiled loops (maizeviz.loops calls its mz_* functions through ctypes).",
    -1, NULL, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__loops(void) {
    PyObject *m = PyModule_Create(&mz_module);
    if (m == NULL) return NULL;
    if (PyModule_AddStringConstant(m, "source_sha256", MZ_STR(MZ_SOURCE_SHA256)) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
