/* Ray packets for maizeviz: batches of rays traced through Embree 4's rtcIntersectN /
 * rtcOccludedN (N = 4, 8 or 16), results written into numpy arrays.
 *
 * No Embree header and no link: the Embree functions come in as addresses (taken by ctypes
 * from the libembree4 that embreex loads), and the structs below are declared from Embree 4's
 * public API (include/embree4/rtcore_ray.h and rtcore_scene.h of Embree 4.4, the version
 * embreex 4.4 vendors). Only their leading fields are written or read; Embree may append
 * fields to a hit (instance arrays, deeper instancing), so every hit packet is followed by
 * slack it may write into.
 *
 * Each function loops over its rays in packets of N, in order; the last packet is masked.
 * Rays are set up exactly as embreex's EmbreeScene.run sets its single rays (tnear 0, mask
 * all ones, time 0, flags 0, ids invalid), so a packet gives the hits Intersect1 gives.
 *
 * Built when maizeviz is installed, as the extension module maizeviz.mesh._packets (setup.py:
 * gcc and clang with -ffp-contract=off, MSVC with /fp:precise, so that float64 steps round
 * as numpy's do), with Python's stable ABI; packets.py imports it and calls the mz_* functions
 * below through ctypes (which releases the GIL). The module itself only tells its source's
 * hash and the packet layout.
 */

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <stdint.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#if defined(_MSC_VER)
#include <malloc.h>
#define MZ_ALIGNED(x) __declspec(align(x))
#define MZ_EXPORT __declspec(dllexport)
#define mz_aligned_alloc(a, size) _aligned_malloc((size), (a))
#define mz_aligned_free _aligned_free
#else
#define MZ_ALIGNED(x) __attribute__((aligned(x)))
#define MZ_EXPORT __attribute__((visibility("default")))
#define mz_aligned_alloc(a, size) aligned_alloc((a), (size))
#define mz_aligned_free free
#endif

#define INVALID_ID 0xFFFFFFFFu
#define QUERY_FLAG_COHERENT (1u << 16)     /* RTC_RAY_QUERY_FLAG_COHERENT */
#define FEATURE_FLAG_ALL 0xFFFFFFFFu        /* RTC_FEATURE_FLAG_ALL */
#define SLACK 4096                          /* bytes Embree may write past our hit fields */

/* RTCIntersectArguments / RTCOccludedArguments (same layout); the trailing pad covers the
 * optional minWidthDistanceFactor of builds with RTC_MIN_WIDTH. */
typedef struct {
    uint32_t flags;
    uint32_t feature_mask;
    void *context;
    void *filter;
    void *callback;
    float pad[4];
} query_args;

#define DECLARE_PACKET(W)                                                                   \
    typedef struct MZ_ALIGNED(64) {                                                         \
        float org_x[W], org_y[W], org_z[W], tnear[W];                                       \
        float dir_x[W], dir_y[W], dir_z[W], time[W];                                        \
        float tfar[W];                                                                      \
        uint32_t mask[W], id[W], flags[W];                                                  \
    } ray##W;                                                                               \
    typedef struct MZ_ALIGNED(64) {                                                         \
        float ng_x[W], ng_y[W], ng_z[W], u[W], v[W];                                        \
        uint32_t prim_id[W], geom_id[W], inst_id[W];                                        \
        char slack[SLACK];                                                                  \
    } hit##W;                                                                               \
    typedef struct MZ_ALIGNED(64) {                                                         \
        ray##W ray;                                                                         \
        hit##W hit;                                                                         \
    } rayhit##W;                                                                            \
    typedef void (*intersect##W##_fn)(const int *, void *, rayhit##W *, query_args *);       \
    typedef void (*occluded##W##_fn)(const int *, void *, ray##W *, query_args *);

DECLARE_PACKET(4)
DECLARE_PACKET(8)
DECLARE_PACKET(16)

static void init_args(query_args *a, int coherent) {
    memset(a, 0, sizeof(*a));
    a->flags = coherent ? QUERY_FLAG_COHERENT : 0u;
    a->feature_mask = FEATURE_FLAG_ALL;
}

/* Which rays go into each packet: in order (row == 0), or, for rays laid out row by row
 * (row rays a row, as a regular grid), in tiles of th rows by W / th columns, so that a
 * packet's rays are neighbours in both directions (Embree traverses compact packets faster). */
typedef struct {
    int64_t n, row, next, r0, c0;
    int th, tw;
} packet_order;

static void order_init(packet_order *o, int64_t n, int64_t row, int width) {
    o->n = n; o->row = row > 1 ? row : 0; o->next = 0; o->r0 = 0; o->c0 = 0;
    o->th = width >= 16 ? 4 : 2;
    o->tw = width / o->th;
}

/* The next packet's ray indices into idx[0, m); returns m (0 when all rays are done). */
static int order_next(packet_order *o, int width, int64_t *idx) {
    int m = 0;
    if (!o->row) {
        for (; m < width && o->next < o->n; ++m) idx[m] = o->next++;
        return m;
    }
    while (m == 0 && o->r0 * o->row < o->n) {
        for (int a = 0; a < o->th; ++a)
            for (int b = 0; b < o->tw; ++b) {
                int64_t c = o->c0 + b, j = (o->r0 + a) * o->row + c;
                if (c < o->row && j < o->n) idx[m++] = j;
            }
        o->c0 += o->tw;
        if (o->c0 >= o->row) { o->c0 = 0; o->r0 += o->th; }
    }
    return m;
}

/* Fill lanes [0, m) of packet r from rays idx[0, m); the rest are masked off in valid. */
#define FILL_RAYS(W, r, valid, idx, m)                                                      \
    for (int k = 0; k < W; ++k) {                                                           \
        int64_t j = idx[k < (m) ? k : 0];                                                   \
        int64_t d = dir_step ? j : 0;                                                       \
        (valid)[k] = k < (m) ? -1 : 0;                                                      \
        (r)->org_x[k] = org[3 * j]; (r)->org_y[k] = org[3 * j + 1];                         \
        (r)->org_z[k] = org[3 * j + 2]; (r)->tnear[k] = 0.0f;                               \
        (r)->dir_x[k] = dir[3 * d]; (r)->dir_y[k] = dir[3 * d + 1];                         \
        (r)->dir_z[k] = dir[3 * d + 2]; (r)->time[k] = 0.0f;                                \
        (r)->tfar[k] = tfar ? tfar[j] : 1e37f;                                              \
        (r)->mask[k] = INVALID_ID; (r)->id[k] = 0; (r)->flags[k] = 0;                       \
    }

/* Packets are filled, traced and read back BLOCK at a time: filling a packet right after
 * Embree has written into the same memory (its masked store of tfar) stalls on the stores;
 * a block keeps the fill, the traversal and the read-out apart (occlusion 7-12 % faster a
 * core). The periodic passes below fill one packet at a time: blocks measured no faster
 * there, where the lanes' float64 segments cost more than the fill. */
#define BLOCK 32

/* The next block of packets of the order: their ray indices idx[b][0, m[b]); returns how
 * many packets (0 when all rays are done). */
static int block_next(packet_order *po, int width, int64_t (*idx)[16], int *m) {
    int nb = 0;
    while (nb < BLOCK && (m[nb] = order_next(po, width, idx[nb])) > 0) ++nb;
    return nb;
}

#define INTERSECT_BODY(W)                                                                   \
    {                                                                                       \
        rayhit##W *rh = (rayhit##W *)mz_aligned_alloc(64, BLOCK * sizeof(rayhit##W));       \
        int (*valid)[W] = (int (*)[W])mz_aligned_alloc(64, BLOCK * W * sizeof(int));        \
        intersect##W##_fn fn = (intersect##W##_fn)fn_addr;                                  \
        int64_t idx[BLOCK][16];                                                             \
        int m[BLOCK];                                                                       \
        packet_order po;                                                                    \
        if (!rh || !valid) { mz_aligned_free(rh); mz_aligned_free(valid); return -3; }      \
        order_init(&po, n, row, W);                                                         \
        for (int nb; (nb = block_next(&po, W, idx, m)) > 0;) {                              \
            for (int b = 0; b < nb; ++b) {                                                  \
                FILL_RAYS(W, &rh[b].ray, valid[b], idx[b], m[b])                            \
                for (int k = 0; k < W; ++k) {                                               \
                    rh[b].hit.geom_id[k] = INVALID_ID; rh[b].hit.prim_id[k] = INVALID_ID;   \
                    rh[b].hit.inst_id[k] = INVALID_ID;                                      \
                }                                                                           \
            }                                                                               \
            for (int b = 0; b < nb; ++b) fn(valid[b], scene, &rh[b], &args);                \
            for (int b = 0; b < nb; ++b)                                                    \
                for (int k = 0; k < m[b]; ++k) {                                            \
                    int64_t j = idx[b][k];                                                  \
                    uint32_t p = rh[b].hit.prim_id[k];                                      \
                    if (prim_out) prim_out[j] = p == INVALID_ID ? -1 : (int32_t)p;          \
                    if (tfar_out) tfar_out[j] = rh[b].ray.tfar[k];                          \
                    if (inst_out)                                                           \
                        inst_out[j] = p == INVALID_ID ? -1 : (int32_t)rh[b].hit.inst_id[k]; \
                }                                                                           \
        }                                                                                   \
        mz_aligned_free(rh);                                                                \
        mz_aligned_free(valid);                                                             \
    }

/* Nearest hits of n rays: origins org (n, 3), directions dir (n, 3) (dir_step 1) or one
 * direction (dir_step 0), ray lengths tfar (n,) or NULL (unbounded). Writes prim_out (n,)
 * int32 (-1: no hit) and tfar_out (n,) float32 (the hit distance, or the ray's tfar where
 * none) and inst_out (n,) int32, the instance hit in a scene of instances (-1: none); any
 * may be NULL. coherent: Embree's coherent-rays flag. row: rays per row when
 * the rays form a grid laid out row by row (packets then take tiles of it), else 0.
 * Returns 0, -1 for an unknown packet width, -3 when memory runs out. */
MZ_EXPORT int mz_intersect(void *fn_addr, int width, void *scene, int64_t n,
                           const float *org, const float *dir, int dir_step,
                           const float *tfar, int32_t *prim_out, float *tfar_out,
                           int32_t *inst_out, int coherent, int64_t row) {
    query_args args;
    init_args(&args, coherent);
    switch (width) {
    case 4: INTERSECT_BODY(4) break;
    case 8: INTERSECT_BODY(8) break;
    case 16: INTERSECT_BODY(16) break;
    default: return -1;
    }
    return 0;
}

#define OCCLUDED_BODY(W)                                                                    \
    {                                                                                       \
        ray##W *r = (ray##W *)mz_aligned_alloc(64, BLOCK * sizeof(ray##W));                 \
        int (*valid)[W] = (int (*)[W])mz_aligned_alloc(64, BLOCK * W * sizeof(int));        \
        occluded##W##_fn fn = (occluded##W##_fn)fn_addr;                                    \
        int64_t idx[BLOCK][16];                                                             \
        int m[BLOCK];                                                                       \
        packet_order po;                                                                    \
        if (!r || !valid) { mz_aligned_free(r); mz_aligned_free(valid); return -3; }        \
        order_init(&po, n, row, W);                                                         \
        for (int nb; (nb = block_next(&po, W, idx, m)) > 0;) {                              \
            for (int b = 0; b < nb; ++b) FILL_RAYS(W, &r[b], valid[b], idx[b], m[b])        \
            for (int b = 0; b < nb; ++b) fn(valid[b], scene, &r[b], &args);                 \
            for (int b = 0; b < nb; ++b)          /* Embree sets -inf where blocked */      \
                for (int k = 0; k < m[b]; ++k) out[idx[b][k]] = r[b].tfar[k] < 0.0f;        \
        }                                                                                   \
        mz_aligned_free(r);                                                                 \
        mz_aligned_free(valid);                                                             \
    }

/* Whether anything lies on each of n rays within tfar (as mz_intersect): out (n,) uint8,
 * 1 where blocked; coherent and row as mz_intersect. Returns 0, -1 for an unknown packet
 * width, -3 when memory runs out. */
MZ_EXPORT int mz_occluded(void *fn_addr, int width, void *scene, int64_t n,
                          const float *org, const float *dir, int dir_step, const float *tfar,
                          uint8_t *out, int coherent, int64_t row) {
    query_args args;
    init_args(&args, coherent);
    switch (width) {
    case 4: OCCLUDED_BODY(4) break;
    case 8: OCCLUDED_BODY(8) break;
    case 16: OCCLUDED_BODY(16) break;
    default: return -1;
    }
    return 0;
}

/* ----------------------------------------------------------------------------------------
 * Rays through a periodic field (maizeviz/light/scene/periodic.py, trace_wrapped, is the same
 * algorithm in numpy, operation for operation in float64, so both give the same answers):
 * the scene repeats with period (w, h) from (x0, y0); each ray is traced, cell by cell, from
 * its own origin moved by whole periods (x, y on the grid of step q), with tfar the end of the
 * cell's segment; it is re-anchored on the grid every `anchor_cm` of horizontal travel.
 * wrap = {x0, y0, w, h, q, anchor_cm}.
 */

typedef struct {
    double o[3], d[3], len, at, k, best, start;
    int64_t cell[2], bcell[2];
    int32_t prim, inst;
    int active;
} lane;

/* v rounded to a multiple of q (a power of two), halves to even as numpy's round: adding and
 * taking away 1.5 * 2^52 rounds a double below 2^51 to an integer in the current (nearest)
 * mode, without libm's slow nearbyint; larger ones are integers already. */
static double round_even(double x) {
    const double big = 6755399441055744.0;
    return fabs(x) < 2251799813685248.0 ? (x + big) - big : x;
}

static double snap1(double v, double q) { return round_even(v / q) * q; }

static void lane_init(lane *L, const double *org, const double *dir, double len,
                      const double *wrap) {
    double q = wrap[4];
    L->o[0] = snap1(org[0], q); L->o[1] = snap1(org[1], q); L->o[2] = org[2];
    L->d[0] = dir[0]; L->d[1] = dir[1]; L->d[2] = dir[2];
    L->len = len;
    double h = hypot(L->d[0], L->d[1]);
    L->at = h > 0 ? wrap[5] / h : INFINITY;
    L->k = 0.0;
    L->best = INFINITY;
    L->start = 0.0;
    L->prim = -1;
    L->inst = -1;
    L->bcell[0] = L->bcell[1] = 0;
    for (int a = 0; a < 2; ++a)
        L->cell[a] = (int64_t)floor((L->o[a] - wrap[a]) / wrap[2 + a]);
    L->active = 1;
}

/* This segment of the lane: the query origin qo, its tfar, and what ends it. */
typedef struct {
    double qo[3], t_anchor, t_exit, t_next, end;
    int step[2];
    float tnear, tfar;
} segment;

/* How far (cm) before a segment's start its query begins: more than a cell edge's rounding
 * and than the margin of the copies (maizeviz.light.scene.periodic.COPY_MARGIN_CM). */
#define TNEAR_MARGIN_CM 0.02

static void lane_segment(const lane *L, const double *wrap, segment *S) {
    double q = wrap[4];
    int finite = isfinite(L->at);
    S->t_anchor = finite ? L->k * L->at : 0.0;
    double anchor[3] = {L->o[0], L->o[1], L->o[2]};
    if (L->k > 0) {
        for (int a = 0; a < 3; ++a) anchor[a] = L->o[a] + S->t_anchor * L->d[a];
        anchor[0] = snap1(anchor[0], q);
        anchor[1] = snap1(anchor[1], q);
    }
    double t_axis[2];
    for (int a = 0; a < 2; ++a) {
        double c0 = wrap[a], p = wrap[2 + a], d = L->d[a];
        if (d > 0) t_axis[a] = (c0 + (double)(L->cell[a] + 1) * p - L->o[a]) / d;
        else if (d < 0) t_axis[a] = (c0 + (double)L->cell[a] * p - L->o[a]) / d;
        else t_axis[a] = INFINITY;
    }
    S->t_exit = t_axis[0] < t_axis[1] ? t_axis[0] : t_axis[1];
    for (int a = 0; a < 2; ++a)
        S->step[a] = t_axis[a] <= S->t_exit ? (L->d[a] > 0) - (L->d[a] < 0) : 0;
    S->t_next = finite ? (L->k + 1) * L->at : INFINITY;
    double end = S->t_exit < S->t_next ? S->t_exit : S->t_next;
    S->end = end < L->len ? end : L->len;
    S->qo[0] = anchor[0] - (double)L->cell[0] * wrap[2];
    S->qo[1] = anchor[1] - (double)L->cell[1] * wrap[3];
    S->qo[2] = anchor[2];
    S->tfar = (float)(S->end - S->t_anchor);
    double near = L->start - S->t_anchor - TNEAR_MARGIN_CM;
    S->tnear = near > 0 ? (float)near : 0.0f;
}

/* After the segment's query: done, or on to the next cell and/or anchor. */
static void lane_advance(lane *L, const segment *S, int done) {
    if (done) { L->active = 0; return; }
    L->start = S->end;
    if (S->t_exit <= S->end) { L->cell[0] += S->step[0]; L->cell[1] += S->step[1]; }
    if (S->t_next <= S->end) L->k += 1;
}

/* One pass over the rays still travelling (act[0, n_act), in packets of W): each traces its
 * current segment; those not done are kept, in order, at the front of act. Returns how many. */
#define WRAPPED_PASS(W)                                                                     \
    static int64_t wrapped_pass##W(void *fn, int any_hit, void *scene, query_args *args,     \
                                   lane *st, int64_t *act, int64_t n_act,                   \
                                   const double *wrap) {                                    \
        rayhit##W rh;                                                                       \
        MZ_ALIGNED(64) int valid[W];                                                        \
        segment seg[W];                                                                     \
        int64_t kept = 0;                                                                   \
        for (int64_t i = 0; i < n_act; i += W) {                                            \
            int m = (int)(n_act - i < W ? n_act - i : W);                                   \
            for (int k = 0; k < W; ++k) {                                                   \
                int on = k < m;                                                             \
                lane *L = &st[act[i + (on ? k : 0)]];                                       \
                valid[k] = on ? -1 : 0;                                                     \
                if (on || k == 0) lane_segment(L, wrap, &seg[k]);                           \
                const segment *S = &seg[on ? k : 0];                                        \
                rh.ray.org_x[k] = (float)S->qo[0]; rh.ray.org_y[k] = (float)S->qo[1];       \
                rh.ray.org_z[k] = (float)S->qo[2]; rh.ray.tnear[k] = S->tnear;              \
                rh.ray.dir_x[k] = (float)L->d[0]; rh.ray.dir_y[k] = (float)L->d[1];          \
                rh.ray.dir_z[k] = (float)L->d[2]; rh.ray.time[k] = 0.0f;                    \
                rh.ray.tfar[k] = S->tfar;                                                   \
                rh.ray.mask[k] = INVALID_ID; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;         \
                rh.hit.geom_id[k] = INVALID_ID; rh.hit.prim_id[k] = INVALID_ID;             \
                rh.hit.inst_id[k] = INVALID_ID;                                             \
            }                                                                               \
            if (any_hit) ((occluded##W##_fn)fn)(valid, scene, &rh.ray, args);               \
            else ((intersect##W##_fn)fn)(valid, scene, &rh, args);                          \
            for (int k = 0; k < m; ++k) {                                                   \
                int64_t j = act[i + k];                                                     \
                lane *L = &st[j];                                                           \
                const segment *S = &seg[k];                                                 \
                int done;                                                                   \
                if (any_hit) {                                                              \
                    int hit = rh.ray.tfar[k] < 0.0f;                                        \
                    if (hit) L->prim = 0;                                                   \
                    done = hit || S->end >= L->len;                                         \
                } else {                                                                    \
                    uint32_t p = rh.hit.prim_id[k];                                         \
                    if (p != INVALID_ID) {                                                  \
                        double dist = S->t_anchor + (double)rh.ray.tfar[k];                 \
                        if (dist < L->best) {                                               \
                            L->best = dist; L->prim = (int32_t)p;                           \
                            L->inst = (int32_t)rh.hit.inst_id[k];                           \
                            L->bcell[0] = L->cell[0]; L->bcell[1] = L->cell[1];             \
                        }                                                                   \
                    }                                                                       \
                    done = L->best <= S->end || S->end >= L->len;                           \
                }                                                                           \
                lane_advance(L, S, done);                                                   \
                if (!done) act[kept++] = j;      /* kept <= i + k: never overwrites ahead */ \
            }                                                                               \
        }                                                                                   \
        return kept;                                                                        \
    }

WRAPPED_PASS(4)
WRAPPED_PASS(8)
WRAPPED_PASS(16)

/* Rays through the periodic field `wrap` (see above): origins org (n, 3) and directions dir
 * (n, 3) or one (dir_step 0), float64 cm, lengths length (n,) cm. any_hit: blocked_out (n,)
 * uint8; else prim_out (n,) int32 (-1: none), cell_out (n, 2) int64 (the cell whose copy of
 * the scene holds the hit), dist_out (n,) float64 (inf: none), inst_out (n,) int32 (the
 * instance hit in a scene of instances; may be NULL). With inst_cells (k, 2) int64, the cell
 * of each instance, cell_out is instead that of the instance hit, plus the frame's cell times
 * frame_cells (2,) (instances tiling each frame). Rays are traced segment by
 * segment in passes, the rays still travelling packed together. Returns 0; -1 for an unknown
 * packet width, -2 for a ray that never ends, -3 when memory runs out. */
MZ_EXPORT int mz_wrapped(void *fn_intersect, void *fn_occluded, int width, void *scene,
                         int64_t n, const double *org, const double *dir, int dir_step,
                         const double *length, const double *wrap, int any_hit,
                         int32_t *prim_out, int64_t *cell_out, double *dist_out,
                         int32_t *inst_out, uint8_t *blocked_out, int coherent, int64_t row,
                         const int64_t *inst_cells, const int64_t *frame_cells) {
    if (width != 4 && width != 8 && width != 16) return -1;
    query_args args;
    init_args(&args, coherent);
    lane *st = (lane *)malloc((size_t)(n > 0 ? n : 1) * sizeof(lane));
    int64_t *act = (int64_t *)malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t));
    if (!st || !act) { free(st); free(act); return -3; }
    /* the first pass in the packet order of the grid (compact tiles), then in that order */
    packet_order po;
    int64_t idx[16], n_act = 0;
    order_init(&po, n, row, width);
    for (int m; (m = order_next(&po, width, idx)) > 0;)
        for (int k = 0; k < m; ++k) act[n_act++] = idx[k];
    for (int64_t j = 0; j < n; ++j)
        lane_init(&st[j], org + 3 * j, dir + 3 * (dir_step ? j : 0), length[j], wrap);
    void *fn = any_hit ? fn_occluded : fn_intersect;
    int rc = 0;
    for (int64_t pass = 0; n_act > 0; ++pass) {
        if (pass > 1000000) { rc = -2; break; }
        switch (width) {
        case 4: n_act = wrapped_pass4(fn, any_hit, scene, &args, st, act, n_act, wrap); break;
        case 8: n_act = wrapped_pass8(fn, any_hit, scene, &args, st, act, n_act, wrap); break;
        default: n_act = wrapped_pass16(fn, any_hit, scene, &args, st, act, n_act, wrap);
        }
    }
    for (int64_t j = 0; j < n && rc == 0; ++j) {
        if (any_hit) { blocked_out[j] = st[j].prim >= 0; continue; }
        prim_out[j] = st[j].prim;
        cell_out[2 * j] = st[j].bcell[0];
        cell_out[2 * j + 1] = st[j].bcell[1];
        dist_out[j] = st[j].best;
        if (inst_out) inst_out[j] = st[j].prim >= 0 ? st[j].inst : -1;
        if (inst_cells && st[j].prim >= 0) {   /* the cell of the instance hit, in the field */
            int64_t i = st[j].inst;
            cell_out[2 * j] = inst_cells[2 * i] + st[j].bcell[0] * frame_cells[0];
            cell_out[2 * j + 1] = inst_cells[2 * i + 1] + st[j].bcell[1] * frame_cells[1];
        }
    }
    free(st);
    free(act);
    return rc;
}

/* The size in bytes this file gives a packet of width 16 (ray, then hit without slack), for
 * the loader's check against Embree 4's layout: 12 x 64 + 8 x 64. */
MZ_EXPORT int64_t mz_layout_check(void) {
    return (int64_t)sizeof(ray16) * 1000 + (int64_t)offsetof(rayhit16, hit);
}

/* ---------------------------------------------------------------------------------------- */
/* The Python module: its source's hash (setup.py passes it as MZ_SOURCE_SHA256) and the
 * packet layout, so that the loader can tell a kernel built from another _packets.c. */

#ifndef MZ_SOURCE_SHA256
#define MZ_SOURCE_SHA256 unknown
#endif
#define MZ_STR2(x) #x
#define MZ_STR(x) MZ_STR2(x)

static struct PyModuleDef mz_module = {
    PyModuleDef_HEAD_INIT, "_packets",
    "Embree ray packets (maizeviz.mesh.packets calls its mz_* functions through ctypes).",
    -1, NULL, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__packets(void) {
    PyObject *m = PyModule_Create(&mz_module);
    if (m == NULL) return NULL;
    if (PyModule_AddStringConstant(m, "source_sha256", MZ_STR(MZ_SOURCE_SHA256)) < 0
            || PyModule_AddIntConstant(m, "layout", (long)mz_layout_check()) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
