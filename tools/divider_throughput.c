/* Throughput of the 512-bit divider and square root on this CPU: the floor the bit-exact
 * kernels of the quad-tree build, the beam caster's ray generation and the merge pay per
 * vector (docs/notes/quadtree.md, "the divider floor").
 *
 * Eight independent chains per instruction kind, so the figure is the reciprocal throughput
 * (ns per instruction), not the latency.
 *
 *   gcc -O2 -mavx512f -o /tmp/divider_throughput tools/divider_throughput.c
 *   /tmp/divider_throughput
 *
 * Needs AVX-512 F (the program faults with SIGILL without it).
 */
#include <immintrin.h>
#include <stdio.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

#define N 100000000L

int main(void) {
    __m512d a[8];
    __m512 c[8], q[8];
    for (int i = 0; i < 8; i++) {
        a[i] = _mm512_set1_pd(1.0 + i * 0.1);
        c[i] = _mm512_set1_ps(1.0f + i * 0.1f);
        q[i] = _mm512_set1_ps(2.0f + i * 0.1f);
    }
    const __m512d bd = _mm512_set1_pd(1.0000001);
    const __m512 bs = _mm512_set1_ps(1.0000001f);

    double t0 = now();
    for (long i = 0; i < N / 8; i++)
        for (int j = 0; j < 8; j++) a[j] = _mm512_div_pd(a[j], bd);
    double t1 = now();
    for (long i = 0; i < N / 8; i++)
        for (int j = 0; j < 8; j++) c[j] = _mm512_div_ps(c[j], bs);
    double t2 = now();
    for (long i = 0; i < N / 8; i++)
        for (int j = 0; j < 8; j++) q[j] = _mm512_sqrt_ps(q[j]);
    double t3 = now();

    double sum = 0;
    for (int i = 0; i < 8; i++)
        sum += _mm512_reduce_add_pd(a[i]) + _mm512_reduce_add_ps(c[i]) + _mm512_reduce_add_ps(q[i]);
    printf("vdivpd zmm  %.2f ns per instruction\n", (t1 - t0) / N * 1e9);
    printf("vdivps zmm  %.2f ns per instruction\n", (t2 - t1) / N * 1e9);
    printf("vsqrtps zmm %.2f ns per instruction\n", (t3 - t2) / N * 1e9);
    printf("(checksum %g)\n", sum);
    return 0;
}
