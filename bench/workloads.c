/* Computations a mission might add to the runtime's tick, counted by bench_workloads.py
 * (callgrind, i486 build) to express a workload in cycles per tick as something a
 * scientist recognises. argv[1] names the computation; each runs once on synthetic
 * data whose size is what the computation would see on a glider.
 *
 *   thermocline_fit  T(z) = a + b tanh((z - z0) / h) fitted by 20 Gauss-Newton steps to
 *                    the 256 (depth, temperature) readings of one 40 m profile at 2 s
 *   spectrum_1024    power spectrum of 1024 samples (radix-2 complex FFT), e.g. an
 *                    ADCP beam or a pitch record for wave estimates
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#define N_READINGS 256
#define N_STEPS 20
#define N_FFT 1024

static double depth[N_READINGS], temp[N_READINGS];

/* Solve the 4x4 system a x = b in place by Gaussian elimination with partial pivoting. */
static void solve4(double a[4][4], double b[4])
{
    for (int k = 0; k < 4; k++) {
        int pivot = k;
        for (int i = k + 1; i < 4; i++) {
            if (fabs(a[i][k]) > fabs(a[pivot][k])) {
                pivot = i;
            }
        }
        for (int j = 0; j < 4; j++) {
            double t = a[k][j];
            a[k][j] = a[pivot][j];
            a[pivot][j] = t;
        }
        double t = b[k];
        b[k] = b[pivot];
        b[pivot] = t;
        for (int i = k + 1; i < 4; i++) {
            double f = a[i][k] / a[k][k];
            for (int j = k; j < 4; j++) {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    for (int k = 3; k >= 0; k--) {
        for (int j = k + 1; j < 4; j++) {
            b[k] -= a[k][j] * b[j];
        }
        b[k] /= a[k][k];
    }
}

static double thermocline_fit(void)
{
    double p[4] = {15.0, -4.0, 12.0, 3.0}; /* a, b, z0, h: a first guess */
    for (int step = 0; step < N_STEPS; step++) {
        double jtj[4][4] = {{0}}, jtr[4] = {0};
        for (int i = 0; i < N_READINGS; i++) {
            double u = (depth[i] - p[2]) / p[3];
            double th = tanh(u);
            double sech2 = 1.0 - th * th;
            double g[4] = {1.0, th, -p[1] * sech2 / p[3], -p[1] * sech2 * u / p[3]};
            double r = temp[i] - (p[0] + p[1] * th);
            for (int j = 0; j < 4; j++) {
                jtr[j] += g[j] * r;
                for (int k = 0; k < 4; k++) {
                    jtj[j][k] += g[j] * g[k];
                }
            }
        }
        for (int j = 0; j < 4; j++) {
            jtj[j][j] *= 1.0 + 1e-3; /* Levenberg damping keeps the step bounded */
        }
        solve4(jtj, jtr);
        for (int j = 0; j < 4; j++) {
            p[j] += jtr[j];
        }
    }
    return p[2];
}

static double re[N_FFT], im[N_FFT];

static double spectrum(void)
{
    for (int i = 0, j = 0; i < N_FFT; i++) { /* bit-reversed order */
        if (i < j) {
            double t = re[i];
            re[i] = re[j];
            re[j] = t;
        }
        int bit = N_FFT >> 1;
        for (; j & bit; bit >>= 1) {
            j ^= bit;
        }
        j |= bit;
    }
    for (int len = 2; len <= N_FFT; len <<= 1) {
        double angle = -2.0 * M_PI / len;
        double wr = cos(angle), wi = sin(angle);
        for (int start = 0; start < N_FFT; start += len) {
            double cr = 1.0, ci = 0.0;
            for (int k = 0; k < len / 2; k++) {
                int a = start + k, b = a + len / 2;
                double tr = re[b] * cr - im[b] * ci, ti = re[b] * ci + im[b] * cr;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
                double next = cr * wr - ci * wi;
                ci = cr * wi + ci * wr;
                cr = next;
            }
        }
    }
    double peak = 0.0;
    for (int i = 1; i < N_FFT / 2; i++) {
        double power = re[i] * re[i] + im[i] * im[i];
        peak = power > peak ? power : peak;
    }
    return peak;
}

/* The functions callgrind counts (--toggle-collect=run_*): one run each. */
__attribute__((noinline)) double run_thermocline_fit(void) { return thermocline_fit(); }
__attribute__((noinline)) double run_spectrum_1024(void) { return spectrum(); }

int main(int argc, char **argv)
{
    for (int i = 0; i < N_READINGS; i++) { /* a 40 m profile, thermocline at 14 m */
        depth[i] = 40.0 * i / (N_READINGS - 1);
        temp[i] = 17.0 - 5.0 * tanh((depth[i] - 14.0) / 2.5) + 0.05 * sin(7.0 * i);
    }
    for (int i = 0; i < N_FFT; i++) {
        re[i] = sin(0.3 * i) + 0.5 * sin(0.05 * i);
        im[i] = 0.0;
    }
    double result = 0.0;
    if (argc > 1 && strcmp(argv[1], "thermocline_fit") == 0) {
        result = run_thermocline_fit();
    } else if (argc > 1 && strcmp(argv[1], "spectrum_1024") == 0) {
        result = run_spectrum_1024();
    } else {
        fprintf(stderr, "usage: workloads thermocline_fit|spectrum_1024\n");
        return 2;
    }
    printf("%.6g\n", result);
    return 0;
}
