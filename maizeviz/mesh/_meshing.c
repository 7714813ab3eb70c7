/* Meshing loops for maizeviz that numpy runs as dozens of passes over temporaries: the
 * triangle areas of K = 4 reference grids (what a triangle budget widens its leaves to) and
 * the distances of a splitting's data points from its chords.
 *
 * Each function computes, element by element, exactly the floating-point operations the numpy
 * code it stands for (maizeviz/mesh/measures.py _grid_areas, maizeviz/mesh/simplify.py
 * _segment_distance) performs, in the same order, and leaves every sum whose order numpy
 * chooses (pairwise summation) to numpy: the results are numpy's to the bit, which
 * tests/core/test_meshing_kernel.py checks. Built with -ffp-contract=off (MSVC /fp:precise) so
 * that no multiply and add fuse into one rounding, as numpy's separate calls never do.
 *
 * Built when maizeviz is installed, as the extension module maizeviz.mesh._meshing (setup.py),
 * with Python's stable ABI; maizeviz/mesh/native.py calls the mz_* functions below through
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
#else
#define MZ_EXPORT __attribute__((visibility("default")))
#endif

/* For nl vertex grids (nl, a, b, 3) float64, C order: twice the area of each grid triangle,
 * (p00, p10, p11) into first (nl, a - 1, b - 1) and (p00, p11, p01) into second, 0 where a
 * grid edge of the triangle is no longer than rel_tol2 x the grid's longest squared edge
 * (what _grid_areas leaves out). Each grid's edges and diagonals are computed once, into
 * scratch arrays one coordinate apart, so that the triangles' loop runs in SIMD lanes.
 * Returns 0, or -3 out of memory. */
MZ_EXPORT int mz_grid_twice_areas(const double *vertices, int64_t nl, int64_t a, int64_t b,
                                  double rel_tol2, double *first, double *second) {
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
        for (int64_t i = 0; i + 1 < a; ++i) {
            const double *h0x = hx + i * c, *h0y = hy + i * c, *h0z = hz + i * c;
            const double *h0s = hs + i * c, *h1s = h0s + c;
            const double *w0x = wx + i * b, *w0y = wy + i * b, *w0z = wz + i * b;
            const double *w0s = ws + i * b, *w1s = w0s + 1;
            const double *ex = dx + i * c, *ey = dy + i * c, *ez = dz + i * c;
            double *o0 = t0 + i * c, *o1 = t1 + i * c;
            for (int64_t j = 0; j < c; ++j) {
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
    }
    free(buf);
    return 0;
}

/* np.maximum(x, lo) then np.minimum(., hi): NaN stays NaN (the sign of a zero returned may
 * differ from numpy's, which no result here can show: t only scales an edge whose product is
 * subtracted and squared). */
static double clamp_nan(double x, double lo, double hi) {
    if (x != x) return x;
    x = x >= lo ? x : lo;
    return x <= hi ? x : hi;
}

/* For R lines of nl grids whose x, y, z are three (nl, m, n) float64 arrays (C order): the
 * largest distance of line[r]'s n points of grid leaf[r] from the chords joining, point by
 * point, lines lo[r] and hi[r] of that grid, as simplify.py's _segment_distance(...).max()
 * computes it (a NaN if any distance is). Returns 0. */
MZ_EXPORT int mz_chord_errors(const double *x, const double *y, const double *z, int64_t m,
                              int64_t n, int64_t r_count, const int64_t *leaf,
                              const int64_t *line, const int64_t *lo, const int64_t *hi,
                              double *out) {
    for (int64_t r = 0; r < r_count; ++r) {
        const int64_t g = leaf[r] * m * n;
        const int64_t p = g + line[r] * n, a = g + lo[r] * n, b = g + hi[r] * n;
        double best = 0.0, nan_value = 0.0;
        int nan = 0;
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
            const double t = clamp_nan(dot / (denom > 0 ? denom : 1.0), 0.0, 1.0);
            const double dx = apx - t * abx, dy = apy - t * aby, dz = apz - t * abz;
            double d2 = dx * dx;
            d2 += dy * dy;
            d2 += dz * dz;
            const double d = sqrt(d2);
            if (d != d) {
                if (!nan) nan_value = d;
                nan = 1;
            } else if (j == 0 || d > best) {
                best = d;
            }
        }
        out[r] = nan ? nan_value : best;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* The Python module: its source's hash (setup.py passes it as MZ_SOURCE_SHA256), so that the
 * loader can tell a module built from another _meshing.c. */

#ifndef MZ_SOURCE_SHA256
#define MZ_SOURCE_SHA256 unknown
#endif
#define MZ_STR2(x) #x
#define MZ_STR(x) MZ_STR2(x)

static struct PyModuleDef mz_module = {
    PyModuleDef_HEAD_INIT, "_meshing",
    "Meshing loops (maizeviz.mesh.native calls its mz_* functions through ctypes).",
    -1, NULL, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__meshing(void) {
    PyObject *m = PyModule_Create(&mz_module);
    if (m == NULL) return NULL;
    if (PyModule_AddStringConstant(m, "source_sha256", MZ_STR(MZ_SOURCE_SHA256)) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
