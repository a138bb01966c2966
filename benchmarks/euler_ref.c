/* Plain C reference of the paper's Euler scheme (eqs. 1-7, linear valve, step input),
 * scenarios in parallel with OpenMP. Build: gcc -O3 -fopenmp -o euler_ref euler_ref.c -lm
 * Usage: euler_ref N NSTEPS  -> prints "seconds checksum". Same parameters as the
 * throughput workload's base scenario (load 6, raising), K varied by +-1e-6 per scenario. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <omp.h>

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 2000;
    long nsteps = argc > 2 ? atol(argv[2]) : 100000;
    const double A = 303e-6, eo = 0.75e-3, beta = 3.4e8, ps = 31e5, r = 0.02, nr = 2.0;
    const double L = 487.8e-15, V = 2.7850404069345122e-06, W = 18.73, X = 0.276, I = 0.146;
    const double th_h = M_PI / 6, h = 10e-6;
    double *xf = malloc(sizeof(double) * n);
    double t0 = omp_get_wtime();
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; i++) {
        double K = 9.4394887e-06 * (1.0 + 1e-6 * i);
        double Kq = K * sqrt(0.5 * ps);
        double th = -M_PI / 3, om = 0.0;
        double p = W * X * cos(th - th_h) / (A * r / nr);
        double y1 = r * sin((M_PI / 3) / nr);
        for (long k = 0; k < nsteps; k++) {
            double x = r * sin(th / nr);
            double xd = r * cos(th / nr) * om / nr;
            double e = y1 - x;
            if (e > eo) e = eo;
            if (e < -eo) e = -eo;
            p += h * beta / V * (Kq * e - A * xd - 2.0 * L * p);
            om += h * (A * p * r / nr - W * X * cos(th - th_h)) / I;
            th += h * om;
        }
        xf[i] = r * sin(th / nr);
    }
    double dt = omp_get_wtime() - t0;
    double s = 0;
    for (int i = 0; i < n; i++) s += xf[i];
    printf("%.6f %.12g\n", dt, s);
    return 0;
}
