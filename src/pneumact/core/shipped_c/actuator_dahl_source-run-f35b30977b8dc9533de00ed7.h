#include <stdint.h>

typedef struct pa_chunk pa_chunk;
typedef struct { pa_chunk *first, *current; int failed; } pa_arena;

void pa_arena_reset(pa_arena *m);
void pa_arena_free(pa_arena *m);
typedef struct { double *data; int64_t shape[1]; int64_t strides[1]; } pa_arr_float64_1d;
typedef struct { int64_t *data; int64_t shape[1]; int64_t strides[1]; } pa_arr_int64_1d;
typedef struct { double f0; double f1; } pa_tuple_2;
typedef struct { double f0; double f1; double f2; } pa_tuple_3;
typedef struct { double f0; double f1; double f2; double f3; double f4; double f5; } pa_tuple_4;
typedef struct { double f0; double f1; double f2; double f3; } pa_tuple_5;
typedef struct { double *data; int64_t shape[2]; int64_t strides[2]; } pa_arr_float64_2d;
typedef struct { double f0; double f1; pa_tuple_3 f2; } pa_tuple_7;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_8;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_9;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_10;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_11;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_12;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_13;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_14;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_15;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_16;
typedef struct { int64_t f0; } pa_tuple_17;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_18;
typedef struct { uint8_t *data; int64_t shape[1]; int64_t strides[1]; } pa_arr_bool_1d;
typedef struct { double f0; int f1; } pa_tuple_20;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_21;
typedef struct { double f0; int f1; } pa_tuple_22;
typedef struct { double f0; int f1; } pa_tuple_23;
typedef struct { int f0; int f1; int f2; } pa_tuple_24;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_25;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_26;

void pa_derive(pa_arr_float64_1d a0);
void pa_initial_state(double a0, double a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3, pa_arr_int64_1d a4, pa_arr_float64_1d a5);
void pa_state_scales(pa_arr_float64_1d a0, pa_arr_float64_1d a1);
void pa_rhs(double a0, double a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3, pa_arr_float64_1d a4, pa_arr_int64_1d a5, pa_arr_float64_1d a6);
void pa_jac(double a0, double a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3, pa_arr_float64_1d a4, pa_arr_int64_1d a5, pa_arr_float64_2d a6);
void pa_outputs(double a0, double a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3, pa_arr_float64_1d a4, pa_arr_int64_1d a5, pa_arr_float64_1d a6);
pa_arr_float64_1d pa_integrate_rodas4(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1, pa_arr_float64_1d a2, pa_arr_int64_1d a3, pa_arr_float64_1d a4, pa_arr_float64_1d a5, double a6, pa_arr_float64_1d a7, double a8, double a9, int64_t a10, pa_arr_float64_2d a11, pa_arr_float64_2d a12, pa_arr_float64_1d a13);
