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
 * Build: cc -O2 -shared -fPIC _packets.c -o _packets.so  (maizeviz/mesh/packets.py does it).
 */

#include <stdint.h>
#include <stddef.h>
#include <string.h>
#include <math.h>

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
    typedef struct {                                                                        \
        float org_x[W], org_y[W], org_z[W], tnear[W];                                       \
        float dir_x[W], dir_y[W], dir_z[W], time[W];                                        \
        float tfar[W];                                                                      \
        uint32_t mask[W], id[W], flags[W];                                                  \
    } __attribute__((aligned(64))) ray##W;                                                  \
    typedef struct {                                                                        \
        float ng_x[W], ng_y[W], ng_z[W], u[W], v[W];                                        \
        uint32_t prim_id[W], geom_id[W], inst_id[W];                                        \
        char slack[SLACK];                                                                  \
    } __attribute__((aligned(64))) hit##W;                                                  \
    typedef struct {                                                                        \
        ray##W ray;                                                                         \
        hit##W hit;                                                                         \
    } __attribute__((aligned(64))) rayhit##W;                                               \
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

#define INTERSECT_BODY(W)                                                                   \
    {                                                                                       \
        rayhit##W rh;                                                                       \
        int valid[W] __attribute__((aligned(64)));                                          \
        intersect##W##_fn fn = (intersect##W##_fn)fn_addr;                                  \
        int64_t idx[W];                                                                     \
        packet_order po;                                                                    \
        order_init(&po, n, row, W);                                                         \
        for (int m; (m = order_next(&po, W, idx)) > 0;) {                                   \
            FILL_RAYS(W, &rh.ray, valid, idx, m)                                            \
            for (int k = 0; k < W; ++k) {                                                   \
                rh.hit.geom_id[k] = INVALID_ID; rh.hit.prim_id[k] = INVALID_ID;             \
                rh.hit.inst_id[k] = INVALID_ID;                                             \
            }                                                                               \
            fn(valid, scene, &rh, &args);                                                   \
            for (int k = 0; k < m; ++k) {                                                   \
                uint32_t p = rh.hit.prim_id[k];                                             \
                if (prim_out) prim_out[idx[k]] = p == INVALID_ID ? -1 : (int32_t)p;         \
                if (tfar_out) tfar_out[idx[k]] = rh.ray.tfar[k];                            \
            }                                                                               \
        }                                                                                   \
    }

/* Nearest hits of n rays: origins org (n, 3), directions dir (n, 3) (dir_step 1) or one
 * direction (dir_step 0), ray lengths tfar (n,) or NULL (unbounded). Writes prim_out (n,)
 * int32 (-1: no hit) and tfar_out (n,) float32 (the hit distance, or the ray's tfar where
 * none); either may be NULL. coherent: Embree's coherent-rays flag. row: rays per row when
 * the rays form a grid laid out row by row (packets then take tiles of it), else 0.
 * Returns 0, or -1 for an unknown packet width. */
int mz_intersect(void *fn_addr, int width, void *scene, int64_t n, const float *org,
                 const float *dir, int dir_step, const float *tfar, int32_t *prim_out,
                 float *tfar_out, int coherent, int64_t row) {
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
        ray##W r;                                                                           \
        int valid[W] __attribute__((aligned(64)));                                          \
        occluded##W##_fn fn = (occluded##W##_fn)fn_addr;                                    \
        int64_t idx[W];                                                                     \
        packet_order po;                                                                    \
        order_init(&po, n, row, W);                                                         \
        for (int m; (m = order_next(&po, W, idx)) > 0;) {                                   \
            FILL_RAYS(W, &r, valid, idx, m)                                                 \
            fn(valid, scene, &r, &args);                                                    \
            for (int k = 0; k < m; ++k)                                                     \
                out[idx[k]] = r.tfar[k] < 0.0f ? 1 : 0; /* Embree sets -inf when blocked */ \
        }                                                                                   \
    }

/* Whether anything lies on each of n rays within tfar (as mz_intersect): out (n,) uint8,
 * 1 where blocked; coherent and row as mz_intersect. Returns 0, or -1 for an unknown
 * packet width. */
int mz_occluded(void *fn_addr, int width, void *scene, int64_t n, const float *org,
                const float *dir, int dir_step, const float *tfar, uint8_t *out, int coherent,
                int64_t row) {
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

/* The size in bytes this file gives a packet of width 16 (ray, then hit without slack), for
 * the loader's check against Embree 4's layout: 12 x 64 + 8 x 64. */
int64_t mz_layout_check(void) {
    return (int64_t)sizeof(ray16) * 1000 + (int64_t)offsetof(rayhit16, hit);
}
