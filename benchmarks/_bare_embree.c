/* Bare Embree's rate on a batch of ray packets, for benchmarks/bench_rays.py: the packets
 * are laid out in memory beforehand (every field set, 64-byte aligned), and the timed call
 * does nothing but call rtcOccluded8 on each in turn, with the coherent flag. No maizeviz
 * code runs around Embree: this is the ceiling of maizeviz.mesh.packets' occlusion on the
 * same rays, in the same packets.
 *
 * As maizeviz/mesh/_packets.c, no Embree header and no link: the function comes in as an
 * address, the structs are Embree 4's RTCRay8 and RTCOccludedArguments.
 *
 * Build: cc -O2 -shared -fPIC _bare_embree.c -o _bare_embree.so (the benchmark does it).
 */

#include <stdint.h>
#include <string.h>

typedef struct {
    uint32_t flags;
    uint32_t feature_mask;
    void *context;
    void *filter;
    void *callback;
    float pad[4];
} query_args;

typedef struct {
    float org_x[8], org_y[8], org_z[8], tnear[8];
    float dir_x[8], dir_y[8], dir_z[8], time[8];
    float tfar[8];
    uint32_t mask[8], id[8], flags[8];
} __attribute__((aligned(64))) ray8;

typedef void (*occluded8_fn)(const int *, void *, ray8 *, query_args *);

/* Lay out packets: packet p takes rays idx[8 p, 8 p + 8) (-1: an empty lane) from origins
 * org (n, 3), one direction dir (3,), lengths tfar (n,); valid (npk, 8) is set to match. */
void bare_prepare(int64_t npk, const int64_t *idx, const float *org, const float *dir,
                  const float *tfar, ray8 *packets, int32_t *valid) {
    for (int64_t p = 0; p < npk; ++p) {
        ray8 *r = &packets[p];
        for (int k = 0; k < 8; ++k) {
            int64_t j = idx[8 * p + k] >= 0 ? idx[8 * p + k] : idx[8 * p];
            valid[8 * p + k] = idx[8 * p + k] >= 0 ? -1 : 0;
            r->org_x[k] = org[3 * j]; r->org_y[k] = org[3 * j + 1]; r->org_z[k] = org[3 * j + 2];
            r->tnear[k] = 0.0f; r->time[k] = 0.0f;
            r->dir_x[k] = dir[0]; r->dir_y[k] = dir[1]; r->dir_z[k] = dir[2];
            r->tfar[k] = tfar[j];
            r->mask[k] = 0xFFFFFFFFu; r->id[k] = 0; r->flags[k] = 0;
        }
    }
}

/* Trace packets [0, npk): Embree sets tfar to -inf in each ray blocked. */
void bare_occluded8(void *fn, void *scene, int64_t npk, const int32_t *valid, ray8 *packets) {
    query_args args;
    memset(&args, 0, sizeof(args));
    args.flags = 1u << 16;                  /* RTC_RAY_QUERY_FLAG_COHERENT */
    args.feature_mask = 0xFFFFFFFFu;        /* RTC_FEATURE_FLAG_ALL */
    occluded8_fn f = (occluded8_fn)fn;
    for (int64_t p = 0; p < npk; ++p) f((const int *)&valid[8 * p], scene, &packets[p], &args);
}
