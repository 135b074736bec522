/* A minimal Embree C harness: traces the rays `irsig bench trace --dump DIR`
 * wrote, on the same triangles, with Embree's own C API and nothing of irsig
 * around it, to show what Embree itself reaches on these rays (docs/embree.md,
 * "Why primary rays are not 3x obvhs").
 *
 *   harness DIR THREADS ROUNDS [robust|fast] [low|medium|high]
 *
 * Builds one scene (one triangle geometry, the given scene flags and build
 * quality), then per ray class and mode traces every batch of the dump
 * (batches shared among THREADS pthreads through an atomic counter, as
 * rayon shares irsig's) and prints the best of ROUNDS in Mray/s, plus the
 * number of hits (or occluded rays) to compare with irsig's answers.
 * Environment: HARNESS_EMBREE_CONFIG is appended to the device's
 * configuration string (e.g. `isa=avx2`); HARNESS_CPU_TIME=1 times with the
 * process's CPU clock instead of the wall clock (rates per CPU-second, which
 * a shared machine's load skews far less; use THREADS 1 with it).
 * Embree 3 API (Debian 12's libembree-dev). */
#define _POSIX_C_SOURCE 200809L
#include <embree3/rtcore.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Embree 3's C headers declare structs without typedefs. */
typedef struct RTCRayHit RTCRayHit;
typedef struct RTCRayHit4 RTCRayHit4;
typedef struct RTCRayHit8 RTCRayHit8;
typedef struct RTCRayHit16 RTCRayHit16;
typedef struct RTCIntersectContext RTCIntersectContext;

typedef struct { float o[3], d[3], tnear, tfar; } Ray;
typedef struct { Ray *rays; uint64_t *bounds; size_t nrays, nb; } Set;

static void *slurp(const char *dir, const char *name, size_t *len) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "rb");
  if (!f) { fprintf(stderr, "harness: cannot open %s\n", path); exit(2); }
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  void *p = aligned_alloc(64, ((size_t)n + 63) / 64 * 64 + 64);
  if (!p || fread(p, 1, (size_t)n, f) != (size_t)n) { fprintf(stderr, "harness: cannot read %s\n", path); exit(2); }
  fclose(f);
  *len = (size_t)n;
  return p;
}

static Set load_set(const char *dir, const char *cls) {
  char name[256];
  size_t n;
  Set s;
  snprintf(name, sizeof name, "%s.rays", cls);
  s.rays = slurp(dir, name, &n);
  s.nrays = n / sizeof(Ray);
  snprintf(name, sizeof name, "%s.bounds", cls);
  s.bounds = slurp(dir, name, &n);
  s.nb = n / 8 - 1;
  return s;
}

enum Mode { SINGLE, P4, P8, P16 };
static const char *mode_name[] = {"single", "packet4", "packet8", "packet16"};

typedef struct {
  RTCScene scene;
  const Set *set;
  int occlusion, mode, coherent;
  atomic_size_t next;
  atomic_size_t answers;
} Job;

static void fill1(RTCRayHit *rh, const Ray *r) {
  rh->ray.org_x = r->o[0]; rh->ray.org_y = r->o[1]; rh->ray.org_z = r->o[2];
  rh->ray.dir_x = r->d[0]; rh->ray.dir_y = r->d[1]; rh->ray.dir_z = r->d[2];
  rh->ray.tnear = r->tnear; rh->ray.tfar = r->tfar; rh->ray.time = 0;
  rh->ray.mask = 0xFFFFFFFF; rh->ray.id = 0; rh->ray.flags = 0;
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID; rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

/* One packet of width W from rays[k..k+n) (n <= W): the SoA layout of
 * RTCRayHitW, written through the generic RTCRayHitN accessors' layout. */
#define PACKET(W)                                                                           \
  static size_t trace##W(RTCScene sc, RTCIntersectContext *ctx, const Ray *rays, size_t n, \
                         int occ) {                                                         \
    RTCRayHit##W rh __attribute__((aligned(64)));                                          \
    int valid[W] __attribute__((aligned(64)));                                             \
    for (int i = 0; i < W; i++) {                                                           \
      const Ray *r = &rays[i < (int)n ? i : 0];                                              \
      valid[i] = i < (int)n ? -1 : 0;                                                       \
      rh.ray.org_x[i] = r->o[0]; rh.ray.org_y[i] = r->o[1]; rh.ray.org_z[i] = r->o[2];      \
      rh.ray.dir_x[i] = r->d[0]; rh.ray.dir_y[i] = r->d[1]; rh.ray.dir_z[i] = r->d[2];      \
      rh.ray.tnear[i] = r->tnear; rh.ray.tfar[i] = r->tfar; rh.ray.time[i] = 0;             \
      rh.ray.mask[i] = 0xFFFFFFFF; rh.ray.id[i] = 0; rh.ray.flags[i] = 0;                   \
      rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;                                           \
      rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;                                        \
    }                                                                                       \
    size_t a = 0;                                                                           \
    if (occ) {                                                                              \
      rtcOccluded##W(valid, sc, ctx, &rh.ray);                                              \
      for (size_t i = 0; i < n; i++) a += rh.ray.tfar[i] < 0;                               \
    } else {                                                                                \
      rtcIntersect##W(valid, sc, ctx, &rh);                                                 \
      for (size_t i = 0; i < n; i++) a += rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;      \
    }                                                                                       \
    return a;                                                                               \
  }
PACKET(4)
PACKET(8)
PACKET(16)

static void *worker(void *arg) {
  Job *j = arg;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = j->coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  size_t answers = 0;
  for (;;) {
    size_t b = atomic_fetch_add(&j->next, 1);
    if (b >= j->set->nb) break;
    size_t lo = j->set->bounds[b], hi = j->set->bounds[b + 1];
    const Ray *rays = j->set->rays;
    if (j->mode == SINGLE) {
      for (size_t k = lo; k < hi; k++) {
        RTCRayHit rh __attribute__((aligned(16)));
        fill1(&rh, &rays[k]);
        if (j->occlusion) {
          rtcOccluded1(j->scene, &ctx, &rh.ray);
          answers += rh.ray.tfar < 0;
        } else {
          rtcIntersect1(j->scene, &ctx, &rh);
          answers += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
      }
    } else {
      size_t w = j->mode == P4 ? 4 : j->mode == P8 ? 8 : 16;
      for (size_t k = lo; k < hi; k += w) {
        size_t n = hi - k < w ? hi - k : w;
        answers += w == 4 ? trace4(j->scene, &ctx, rays + k, n, j->occlusion)
                 : w == 8 ? trace8(j->scene, &ctx, rays + k, n, j->occlusion)
                          : trace16(j->scene, &ctx, rays + k, n, j->occlusion);
      }
    }
  }
  atomic_fetch_add(&j->answers, answers);
  return NULL;
}

static double now(void) {
  struct timespec t;
  const char *cpu = getenv("HARNESS_CPU_TIME");
  clock_gettime(cpu && strcmp(cpu, "1") == 0 ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: harness DIR THREADS ROUNDS [robust|fast] [low|medium|high]\n");
    return 2;
  }
  const char *dir = argv[1];
  int threads = atoi(argv[2]), rounds = atoi(argv[3]);
  int robust = argc < 5 || strcmp(argv[4], "fast") != 0;
  const char *quality = argc < 6 ? "medium" : argv[5];
  const char *extra = getenv("HARNESS_EMBREE_CONFIG");
  char cfg[256];
  snprintf(cfg, sizeof cfg, "threads=%d%s%s", threads, extra ? "," : "", extra ? extra : "");
  RTCDevice dev = rtcNewDevice(cfg);
  size_t n;
  float *tri = slurp(dir, "triangles.f32", &n);
  size_t ntri = n / 36;
  double t0 = now();
  RTCScene sc = rtcNewScene(dev);
  rtcSetSceneFlags(sc, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(sc, strcmp(quality, "high") == 0  ? RTC_BUILD_QUALITY_HIGH
                              : strcmp(quality, "low") == 0 ? RTC_BUILD_QUALITY_LOW
                                                            : RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  /* Vertices as irsig gives them (three per triangle), shared buffer. */
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, tri, 0, 12, ntri * 3 + 1);
  unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, ntri);
  for (size_t i = 0; i < ntri * 3; i++) idx[i] = (unsigned)i;
  rtcCommitGeometry(g);
  rtcAttachGeometry(sc, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(sc);
  double build = now() - t0;
  if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) { fprintf(stderr, "harness: Embree error\n"); return 1; }
  printf("{\"embree\": \"%d.%d.%d\", \"triangles\": %zu, \"threads\": %d, \"robust\": %s, \"quality\": \"%s\", \"build_s\": %.3f, \"classes\": {",
         (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MAJOR),
         (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MINOR),
         (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_PATCH), ntri, threads,
         robust ? "true" : "false", quality, build);
  const char *classes[] = {"primary", "shadow", "hemisphere", "diffuse"};
  for (int c = 0; c < 4; c++) {
    Set s = load_set(dir, classes[c]);
    printf("%s\"%s\": {\"rays\": %zu", c ? ", " : "", classes[c], s.nrays);
    for (int m = SINGLE; m <= P16; m++) {
      double best = 0;
      size_t answers = 0;
      for (int r = 0; r < rounds; r++) {
        Job j = {sc, &s, c == 1, m, c <= 1, 0, 0};
        pthread_t th[64];
        double a = now();
        for (int t = 0; t < threads && t < 64; t++) pthread_create(&th[t], NULL, worker, &j);
        for (int t = 0; t < threads && t < 64; t++) pthread_join(th[t], NULL);
        double mr = s.nrays / (now() - a) / 1e6;
        if (mr > best) best = mr;
        answers = atomic_load(&j.answers);
      }
      printf(", \"%s_mrays_s\": %.3f, \"%s_answers\": %zu", mode_name[m], best, mode_name[m], answers);
    }
    printf("}");
    fflush(stdout);
    free(s.rays);
    free(s.bounds);
  }
  printf("}}\n");
  rtcReleaseScene(sc);
  rtcReleaseDevice(dev);
  free(tri);
  return 0;
}
