/* A hand-written driver for lsdc's generated C (`lsdc compile --emit c`): Dormand–Prince 5(4)
   with Hairer's step control (Hairer, Nørsett & Wanner, Solving ODEs I, II.4 and II.5: the
   scaled RMS error norm with atol + rtol * max(|y0|, |y1|), the step factor 0.9 err^(-1/5)
   bounded to [0.2, 10], first-same-as-last), no dense output. It runs the runs lsdc sweep runs:
   RUNS initial angles of the first coordinate evenly spaced from FROM to TO (both exactly), the
   other initial values as given, to time T; prints each run's end state and, on standard error,
   the thread CPU time of all the runs. Built by bench/sweep_vs_peers.py with the generated C
   `#include`d:  cc -O2 -DMODEL='"dp.c"' dopri5_driver.c -lm */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include MODEL

enum { S = 2 * N };

static void f(double t, const double *y, double *dy) {
    for (int i = 0; i < N; i++) dy[i] = y[N + i];
    forward_dynamics(t, y, y + N, 0, dy + N);
}

static int integrate(double *y, double end, double tol, long *steps) {
    static const double c2 = 1. / 5, c3 = 3. / 10, c4 = 4. / 5, c5 = 8. / 9;
    static const double a21 = 1. / 5, a31 = 3. / 40, a32 = 9. / 40, a41 = 44. / 45,
                        a42 = -56. / 15, a43 = 32. / 9, a51 = 19372. / 6561,
                        a52 = -25360. / 2187, a53 = 64448. / 6561, a54 = -212. / 729,
                        a61 = 9017. / 3168, a62 = -355. / 33, a63 = 46732. / 5247,
                        a64 = 49. / 176, a65 = -5103. / 18656, a71 = 35. / 384,
                        a73 = 500. / 1113, a74 = 125. / 192, a75 = -2187. / 6784,
                        a76 = 11. / 84;
    static const double e1 = 71. / 57600, e3 = -71. / 16695, e4 = 71. / 1920,
                        e5 = -17253. / 339200, e6 = 22. / 525, e7 = -1. / 40;
    double k1[S], k2[S], k3[S], k4[S], k5[S], k6[S], k7[S], z[S], y1[S];
    double t = 0, h = 1e-3;
    f(t, y, k1);
    while (t < end) {
        if (t + h > end) h = end - t;
        for (int i = 0; i < S; i++) z[i] = y[i] + h * a21 * k1[i];
        f(t + c2 * h, z, k2);
        for (int i = 0; i < S; i++) z[i] = y[i] + h * (a31 * k1[i] + a32 * k2[i]);
        f(t + c3 * h, z, k3);
        for (int i = 0; i < S; i++) z[i] = y[i] + h * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
        f(t + c4 * h, z, k4);
        for (int i = 0; i < S; i++)
            z[i] = y[i] + h * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
        f(t + c5 * h, z, k5);
        for (int i = 0; i < S; i++)
            z[i] = y[i] + h * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
        f(t + h, z, k6);
        for (int i = 0; i < S; i++)
            y1[i] = y[i] + h * (a71 * k1[i] + a73 * k3[i] + a74 * k4[i] + a75 * k5[i] + a76 * k6[i]);
        f(t + h, y1, k7);
        double sum = 0;
        for (int i = 0; i < S; i++) {
            double e = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
            double scale = tol + tol * fmax(fabs(y[i]), fabs(y1[i]));
            sum += (e / scale) * (e / scale);
        }
        double err = sqrt(sum / S);
        double factor = err == 0 ? 10 : fmin(10, fmax(0.2, 0.9 * pow(err, -0.2)));
        if (err <= 1) {
            t += h;
            for (int i = 0; i < S; i++) y[i] = y1[i], k1[i] = k7[i];
            ++*steps;
        }
        h *= factor;
        if (!(h > 1e-14)) return 1;
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 6 + S - 1) {
        fprintf(stderr, "usage: %s RUNS FROM TO T TOL y0[1..%d]\n", argv[0], S - 1);
        return 2;
    }
    int runs = atoi(argv[1]);
    double from = atof(argv[2]), to = atof(argv[3]), end = atof(argv[4]), tol = atof(argv[5]);
    double rest[S];
    for (int i = 1; i < S; i++) rest[i] = atof(argv[5 + i]);
    double *out = malloc(sizeof(double) * S * runs);
    long steps = 0;
    struct timespec a, b;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
    for (int r = 0; r < runs; r++) {
        double *y = out + S * r;
        for (int i = 1; i < S; i++) y[i] = rest[i];
        y[0] = runs == 1 ? from : (r == runs - 1 ? to : from + (to - from) * r / (runs - 1));
        if (integrate(y, end, tol, &steps)) fprintf(stderr, "run %d: step underflow\n", r);
    }
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
    for (int r = 0; r < runs; r++) {
        for (int i = 0; i < S; i++) printf(i ? ",%.17g" : "%.17g", out[S * r + i]);
        printf("\n");
    }
    fprintf(stderr, "cpu %.9f steps %ld\n", (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec), steps);
    free(out);
    return 0;
}
