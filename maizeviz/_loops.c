/* Compiled loops for maizeviz that numpy runs as dozens of passes over temporaries: the
 * triangle areas of K = 4 reference grids (what a triangle budget widens its leaves to), the
 * distances of a splitting's data points from its chords, the B-spline basis matrices
 * every surface is fitted and sampled with, and a mesh file's repeated triangles and areas.
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
#include <string.h>
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
/* Triangles of a mesh file (maizeviz/canopy/from_mesh.py): which repeat an earlier one, and
 * their areas, each in one pass where numpy makes a dozen over temporaries. */

/* A vertex's coordinates as 64-bit patterns, -0.0 read as 0.0 (equal positions, equal bits). */
static void vertex_bits(const double *v, uint64_t out[3]) {
    for (int k = 0; k < 3; ++k) {
        double x = v[k] == 0.0 ? 0.0 : v[k];
        memcpy(&out[k], &x, sizeof x);
    }
}

/* A triangle's corners by position in a fixed order (lexicographic on their bit patterns), so
 * that two triangles of the same three corners, in any order, give the same nine words. */
static void corners_sorted(const double *vertices, const int64_t *f, uint64_t c[9]) {
    uint64_t p[3][3];
    for (int j = 0; j < 3; ++j) vertex_bits(vertices + 3 * f[j], p[j]);
    int o[3] = {0, 1, 2};
    for (int i = 1; i < 3; ++i)
        for (int j = i; j > 0; --j) {
            const uint64_t *a = p[o[j - 1]], *b = p[o[j]];
            int greater = a[0] != b[0] ? a[0] > b[0] : a[1] != b[1] ? a[1] > b[1] : a[2] > b[2];
            if (!greater) break;
            int t = o[j]; o[j] = o[j - 1]; o[j - 1] = t;
        }
    for (int j = 0; j < 3; ++j) memcpy(c + 3 * j, p[o[j]], sizeof p[0]);
}

static uint64_t mix(uint64_t h, uint64_t v) {
    h = (h ^ v) * UINT64_C(0x9E3779B97F4A7C15);
    return h ^ (h >> 31);
}

/* out[t] = 1 where triangle t's three corners (by position, in any order) are those of an
 * earlier triangle, else 0. vertices (nv, 3) float64, faces (nf, 3) int64, C order, nf below
 * 2^31. Each vertex gets a hash of its position, each triangle the sum of its corners' (the
 * same in any order). The triangles are dealt, in order, into parts by their hash's top bits
 * (a counting sort into a few dozen parts, so that each part's table, of 2^17 slots at most,
 * stays in the cache where one table of them all is read at random from memory: at K = 4,
 * 60 ms of CPU against one table's 75); in each part they go in order into
 * an open-addressed table of twice their number (linear probing), and one whose hash is
 * already there is compared corner by corner with the triangles holding it. used, unless
 * NULL, (nv,): 1 for each vertex a triangle uses, else 0. Returns 0, -2 for a negative count,
 * nf of 2^31 or more or a vertex index outside [0, nv) (out not written, used not an answer),
 * -3 out of memory. */
MZ_EXPORT int mz_repeated_triangles(const double *vertices, int64_t nv, const int64_t *faces,
                                    int64_t nf, uint8_t *out, uint8_t *used) {
    if (nv < 0 || nf < 0 || nf >= INT64_C(0x7FFFFFFF)) return -2;
    int pbits = 0;                    /* 2^pbits parts of at most about 2^16 triangles: */
    while (pbits < 16 && (INT64_C(1) << (pbits + 16)) < nf) ++pbits;   /* few streams to deal */
    const int64_t nparts = INT64_C(1) << pbits;
    uint64_t *hv = malloc(sizeof(uint64_t) * (size_t)(nv > 0 ? nv : 1));
    uint64_t *key = malloc(sizeof(uint64_t) * (size_t)(nf > 0 ? nf : 1));
    uint64_t *pkey = malloc(sizeof(uint64_t) * (size_t)(nf > 0 ? nf : 1));
    int32_t *order = malloc(sizeof(int32_t) * (size_t)(nf > 0 ? nf : 1));
    int64_t *start = calloc((size_t)nparts + 1, sizeof(int64_t));
    int64_t *fill = malloc(sizeof(int64_t) * (size_t)nparts);
    int32_t *table = NULL;
    int rc = -3;
    if (hv == NULL || key == NULL || pkey == NULL || order == NULL || start == NULL ||
            fill == NULL)
        goto done;
    for (int64_t i = 0; i < nv; ++i) {
        uint64_t b[3];
        vertex_bits(vertices + 3 * i, b);
        hv[i] = mix(mix(mix(0, b[0]), b[1]), b[2]);
    }
    if (used != NULL) memset(used, 0, (size_t)nv);   /* 1 for each vertex a triangle uses */
    for (int64_t t = 0; t < nf; ++t) {
        const int64_t *f = faces + 3 * t;
        if ((f[0] < 0) | (f[0] >= nv) | (f[1] < 0) | (f[1] >= nv) | (f[2] < 0) | (f[2] >= nv)) {
            rc = -2;
            goto done;
        }
        key[t] = mix(hv[f[0]] + hv[f[1]] + hv[f[2]], 0);
        ++start[pbits ? (int64_t)(key[t] >> (64 - pbits)) + 1 : 1];
        if (used != NULL) used[f[0]] = used[f[1]] = used[f[2]] = 1;
    }
    int64_t most = 0;
    for (int64_t p = 0; p < nparts; ++p) {
        most = start[p + 1] > most ? start[p + 1] : most;
        start[p + 1] += start[p];
        fill[p] = start[p];
    }
    for (int64_t t = 0; t < nf; ++t) {            /* in order within each part */
        const int64_t p = pbits ? (int64_t)(key[t] >> (64 - pbits)) : 0;
        pkey[fill[p]] = key[t];
        order[fill[p]++] = (int32_t)t;
    }
    int tbits = 4;
    while ((INT64_C(1) << tbits) < 2 * most) ++tbits;
    const uint64_t mask = (UINT64_C(1) << tbits) - 1;
    table = malloc(sizeof(int32_t) * (size_t)(mask + 1));
    if (table == NULL) goto done;
    memset(out, 0, (size_t)nf);
    for (int64_t p = 0; p < nparts; ++p) {
        const int64_t a = start[p], n = start[p + 1] - a;
        if (n < 2) continue;
        memset(table, 0xff, sizeof(int32_t) * (size_t)(mask + 1));   /* -1: empty */
        for (int64_t j = 0; j < n; ++j) {
            const uint64_t k = pkey[a + j];
            uint64_t slot = (k >> (64 - pbits - tbits)) & mask;
            for (;; slot = (slot + 1) & mask) {
                const int32_t s = table[slot];
                if (s < 0) {
                    table[slot] = (int32_t)j;
                    break;
                }
                if (pkey[a + s] != k) continue;
                uint64_t c0[9], c1[9];
                corners_sorted(vertices, faces + 3 * (int64_t)order[a + s], c0);
                corners_sorted(vertices, faces + 3 * (int64_t)order[a + j], c1);
                if (memcmp(c0, c1, sizeof c0) == 0) {
                    out[order[a + j]] = 1;
                    break;
                }
            }
        }
    }
    rc = 0;
done:
    free(hv); free(key); free(pkey); free(order); free(start); free(fill); free(table);
    return rc;
}

/* Area (cm2) of each triangle, and (unless centre is NULL) its centroid seen from above (nf, 2),
 * as _areas_centres computes them: per coordinate the corners a, b, d, the centre
 * (a + b + d) / 3, the edges b - a and d - a; the cross product's squared components summed in
 * order x, y, z; half its root. Returns 0, or -2 for a negative count or a vertex index
 * outside [0, nv) (checked as the triangles come: what was written before is not an answer). */
MZ_EXPORT int mz_triangle_areas(const double *vertices, int64_t nv, const int64_t *faces,
                                int64_t nf, double *area, double *centre) {
    if (nv < 0 || nf < 0) return -2;
    for (int64_t t = 0; t < nf; ++t) {
        const int64_t *f = faces + 3 * t;
        if ((f[0] < 0) | (f[0] >= nv) | (f[1] < 0) | (f[1] >= nv) | (f[2] < 0) | (f[2] >= nv))
            return -2;
        const double *a = vertices + 3 * faces[3 * t], *b = vertices + 3 * faces[3 * t + 1],
                     *d = vertices + 3 * faces[3 * t + 2];
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            if (centre != NULL && k < 2) centre[2 * t + k] = (a[k] + b[k] + d[k]) / 3.0;
            e1[k] = b[k] - a[k];
            e2[k] = d[k] - a[k];
        }
        double c = e1[1] * e2[2] - e1[2] * e2[1];
        double s = c * c;
        c = e1[2] * e2[0] - e1[0] * e2[2];
        s += c * c;
        c = e1[0] * e2[1] - e1[1] * e2[0];
        s += c * c;
        area[t] = 0.5 * sqrt(s);
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
