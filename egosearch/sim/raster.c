#include <math.h>
#include <string.h>

#define PIX_EPS 1e-7
static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double dmax(double a, double b) { return a > b ? a : b; }

/* One screen-space triangle: sx, sy pixel coordinates (the centre of pixel column j is at
   j + 0.5), iz = 1 / z-depth at the vertices. Keeps the largest 1/z (nearest surface) per
   pixel in izbuf; with a mask buffer, also marks the pixels this triangle wins. */
static void raster_tri(const double* sx, const double* sy, const double* iz,
                       float* izbuf, unsigned char* mask, int W, int H)
{
    double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
    if (!(fabs(area) > 1e-12)) return;
    double miny = dmin(sy[0], dmin(sy[1], sy[2])), maxy = dmax(sy[0], dmax(sy[1], sy[2]));
    double minx = dmin(sx[0], dmin(sx[1], sx[2])), maxx = dmax(sx[0], dmax(sx[1], sx[2]));
    double fj0 = ceil(dmax(miny - 0.5 - PIX_EPS, -1.0)), fj1 = floor(dmin(maxy - 0.5 + PIX_EPS, (double)H));
    double fi0 = ceil(dmax(minx - 0.5 - PIX_EPS, -1.0)), fi1 = floor(dmin(maxx - 0.5 + PIX_EPS, (double)W));
    int j0 = fj0 < 0 ? 0 : (int)fj0, j1 = fj1 > H - 1 ? H - 1 : (int)fj1;
    int i0 = fi0 < 0 ? 0 : (int)fi0, i1 = fi1 > W - 1 ? W - 1 : (int)fi1;
    if (j0 > j1 || i0 > i1) return;
    /* 1/z is affine over the screen: iz(x, y) = iz0 + A (x - x0) + B (y - y0) */
    double dx1 = sx[1] - sx[0], dy1 = sy[1] - sy[0], dx2 = sx[2] - sx[0], dy2 = sy[2] - sy[0];
    double d1 = iz[1] - iz[0], d2 = iz[2] - iz[0];
    double A = (d1 * dy2 - d2 * dy1) / area, B = (dx1 * d2 - dx2 * d1) / area;
    float izmin = (float)dmin(iz[0], dmin(iz[1], iz[2])), izmax = (float)dmax(iz[0], dmax(iz[1], iz[2]));
    float fA = (float)A;
    /* Each edge bounds x on a row: inside <=> x >= xk(y) (lower) or x <= xk(y) (upper), with
       xk(y) = px + (ex / ey) (y - py). Horizontal edges bound y instead. */
    double s = area > 0 ? 1.0 : -1.0;
    double ex_[3], py_[3], px_[3], slope[3];
    int kind[3]; /* +1 lower bound, -1 upper bound, 0 horizontal */
    for (int k = 0; k < 3; ++k) {
        int q = (k + 1) % 3;
        double ex = sx[q] - sx[k], ey = sy[q] - sy[k];
        double a = -s * ey;
        px_[k] = sx[k]; py_[k] = sy[k]; ex_[k] = s * ex;
        if (a > 0) { kind[k] = 1; slope[k] = ex / ey; }
        else if (a < 0) { kind[k] = -1; slope[k] = ex / ey; }
        else { kind[k] = 0; slope[k] = 0; }
    }
    for (int j = j0; j <= j1; ++j) {
        double yc = j + 0.5;
        double lo = (double)i0, hi = (double)i1;
        int empty = 0;
        for (int k = 0; k < 3; ++k) {
            if (kind[k] > 0) {
                double t = ceil(px_[k] + slope[k] * (yc - py_[k]) - 0.5 - PIX_EPS);
                if (t > lo) lo = t;
            } else if (kind[k] < 0) {
                double t = floor(px_[k] + slope[k] * (yc - py_[k]) - 0.5 + PIX_EPS);
                if (t < hi) hi = t;
            } else if (ex_[k] * (yc - py_[k]) < -PIX_EPS * fabs(ex_[k])) {
                empty = 1;
            }
        }
        if (empty || !(lo <= hi)) continue;
        int ilo = (int)lo, n = (int)hi - ilo + 1;
        float base = (float)(iz[0] + A * (ilo + 0.5 - sx[0]) + B * (yc - sy[0]));
        float* zr = izbuf + (long)j * W + ilo;
        if (mask) {
            unsigned char* mr = mask + (long)j * W + ilo;
            for (int i = 0; i < n; ++i) {
                float v = base + fA * (float)i;
                v = v < izmin ? izmin : v;
                v = v > izmax ? izmax : v;
                if (v > zr[i]) { zr[i] = v; mr[i] = 1; }
            }
        } else {
            for (int i = 0; i < n; ++i) {
                float v = base + fA * (float)i;
                v = v < izmin ? izmin : v;
                v = v > izmax ? izmax : v;
                zr[i] = v > zr[i] ? v : zr[i];
            }
        }
    }
}

/* Near-plane clipping in camera space, projection, rasterisation. cam: see render_frame. */
static void draw_tri(const double* c0, const double* c1, const double* c2, const double* cam,
                     float* izbuf, unsigned char* mask, int W, int H)
{
    const double f = cam[12], near = cam[13];
    const double cx = 0.5 * W, cy = 0.5 * H;
    const double* in[3] = {c0, c1, c2};
    double poly[4][3];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
        const double* a = in[k];
        const double* b = in[(k + 1) % 3];
        int ain = a[2] >= near, bin = b[2] >= near;
        if (ain) { poly[n][0] = a[0]; poly[n][1] = a[1]; poly[n][2] = a[2]; ++n; }
        if (ain != bin) {
            double t = (near - a[2]) / (b[2] - a[2]);
            poly[n][0] = a[0] + t * (b[0] - a[0]);
            poly[n][1] = a[1] + t * (b[1] - a[1]);
            poly[n][2] = near;
            ++n;
        }
    }
    if (n < 3) return;
    double sx[4], sy[4], iz[4];
    for (int k = 0; k < n; ++k) {
        iz[k] = 1.0 / poly[k][2];
        sx[k] = cx + f * poly[k][0] * iz[k];
        sy[k] = cy - f * poly[k][1] * iz[k];
    }
    raster_tri(sx, sy, iz, izbuf, mask, W, H);
    if (n == 4) {
        double tx[3] = {sx[0], sx[2], sx[3]}, ty[3] = {sy[0], sy[2], sy[3]}, tz[3] = {iz[0], iz[2], iz[3]};
        raster_tri(tx, ty, tz, izbuf, mask, W, H);
    }
}

/* Every triangle of every group (part) whose bounding sphere may be in view.
   groups: (ng, 4) int: vertex start, vertex end, triangle start, triangle end.
   spheres: (ng, 4) double: centre xyz, radius.  scratch: 3 doubles per vertex. */
static int draw_mesh(const float* verts, const int* tris, const int* groups, const double* spheres,
                     int ng, double* scratch, const double* cam, float* izbuf, unsigned char* mask,
                     int W, int H)
{
    const double* R = cam + 3;
    const double f = cam[12], near = cam[13], maxd = cam[14];
    const double tx = 0.5 * W / f, ty = 0.5 * H / f;
    const double nx = sqrt(1.0 + tx * tx), ny = sqrt(1.0 + ty * ty);
    int drawn = 0;
    for (int g = 0; g < ng; ++g) {
        const double* sp = spheres + 4 * g;
        double d0 = sp[0] - cam[0], d1 = sp[1] - cam[1], d2 = sp[2] - cam[2], r = sp[3];
        double xc = R[0] * d0 + R[1] * d1 + R[2] * d2;
        double yc = R[3] * d0 + R[4] * d1 + R[5] * d2;
        double zc = R[6] * d0 + R[7] * d1 + R[8] * d2;
        if (zc + r < near || zc - r > maxd) continue;
        if ((xc - tx * zc) / nx > r || (-xc - tx * zc) / nx > r) continue;
        if ((yc - ty * zc) / ny > r || (-yc - ty * zc) / ny > r) continue;
        const int* gr = groups + 4 * g;
        for (int v = gr[0]; v < gr[1]; ++v) {
            double e0 = verts[3 * v] - cam[0], e1 = verts[3 * v + 1] - cam[1], e2 = verts[3 * v + 2] - cam[2];
            double* o = scratch + 3 * v;
            o[0] = R[0] * e0 + R[1] * e1 + R[2] * e2;
            o[1] = R[3] * e0 + R[4] * e1 + R[5] * e2;
            o[2] = R[6] * e0 + R[7] * e1 + R[8] * e2;
        }
        for (int t = gr[2]; t < gr[3]; ++t) {
            const double* a = scratch + 3 * tris[3 * t];
            const double* b = scratch + 3 * tris[3 * t + 1];
            const double* c = scratch + 3 * tris[3 * t + 2];
            if (a[2] < near && b[2] < near && c[2] < near) continue;
            if (a[2] > maxd && b[2] > maxd && c[2] > maxd) continue;
            if (a[0] > tx * a[2] && b[0] > tx * b[2] && c[0] > tx * c[2]) continue;
            if (a[0] < -tx * a[2] && b[0] < -tx * b[2] && c[0] < -tx * c[2]) continue;
            if (a[1] > ty * a[2] && b[1] > ty * b[2] && c[1] > ty * c[2]) continue;
            if (a[1] < -ty * a[2] && b[1] < -ty * b[2] && c[1] < -ty * c[2]) continue;
            draw_tri(a, b, c, cam, izbuf, mask, W, H);
            ++drawn;
        }
    }
    return drawn;
}

/* One frame: the static house, then the target (tng = 0: none) marking the mask, then
   z-depth = 1 / (1/z), clipped to max depth.
   cam: position (3), R (9: rows right, up, forward), f (px), near, max depth. */
int render_frame(const float* sv, const int* st, const int* sg, const double* ss, int sng, double* sscr,
                 const float* tv, const int* tt, const int* tg, const double* ts, int tng, double* tscr,
                 const double* cam, float* izbuf, float* depth, unsigned char* mask, int W, int H)
{
    const float maxd = (float)cam[14], izfar = (float)(1.0 / cam[14]);
    const long np = (long)W * H;
    for (long p = 0; p < np; ++p) izbuf[p] = izfar;
    memset(mask, 0, (size_t)W * (size_t)H);
    int drawn = draw_mesh(sv, st, sg, ss, sng, sscr, cam, izbuf, NULL, W, H);
    if (tng > 0) drawn += draw_mesh(tv, tt, tg, ts, tng, tscr, cam, izbuf, mask, W, H);
    for (long p = 0; p < np; ++p) {
        float z = 1.0f / izbuf[p];
        depth[p] = izbuf[p] > izfar ? (z < maxd ? z : maxd) : maxd;
    }
    return drawn;
}

/* What this library was built from and for: "<source key> <target>", target "portable" or the key
   of the CPU it was tuned for (-march=native). The loader compares it with the raster.c and the CPU
   it has (egosearch/sim/rasterbuild.py); the build passes it as a define. */
#ifndef EGOSEARCH_RASTER_BUILD
#define EGOSEARCH_RASTER_BUILD "unknown"
#endif
const char* egosearch_raster_build(void) { return EGOSEARCH_RASTER_BUILD; }
