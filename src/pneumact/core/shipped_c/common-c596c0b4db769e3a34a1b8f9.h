#include <stdint.h>

typedef struct pa_chunk pa_chunk;
typedef struct { pa_chunk *first, *current; int failed; } pa_arena;

void pa_arena_reset(pa_arena *m);
void pa_arena_free(pa_arena *m);
typedef struct { double *data; int64_t shape[1]; int64_t strides[1]; } pa_arr_float64_1d;
typedef struct { int64_t *data; int64_t shape[1]; int64_t strides[1]; } pa_arr_int64_1d;
typedef struct { int64_t f0; } pa_tuple_2;
typedef struct { double f0; double f1; } pa_tuple_3;
typedef struct { int64_t f0; int64_t f1; int64_t f2; int64_t f3; } pa_tuple_4;
typedef struct { int64_t f0; int64_t f1; int64_t f2; int64_t f3; } pa_tuple_5;
typedef struct { double *data; int64_t shape[2]; int64_t strides[2]; } pa_arr_float64_2d;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_7;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_8;
typedef struct { int64_t f0; int64_t f1; } pa_tuple_9;
typedef struct { double f0; double f1; double f2; } pa_tuple_10;

void pa_eval_many(pa_arr_float64_1d a0, pa_arr_int64_1d a1, int64_t a2, pa_arr_float64_1d a3, pa_arr_float64_1d a4, pa_arr_float64_1d a5);
double pa_stroke(pa_arr_float64_1d a0);
void pa_pressure_features(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3);
void pa_all_features(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1, pa_arr_float64_1d a2, pa_arr_float64_1d a3, int a4, pa_arr_float64_1d a5, pa_arr_float64_1d a6, int a7, pa_arr_float64_1d a8);
double pa_motion_onset(pa_arr_float64_1d a0, pa_arr_float64_1d a1, double a2);
double pa_breakaway(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1);
double pa_sliding_speed(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1, pa_arr_float64_1d a2);
double pa_presliding_travel(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1);
double pa_loop_width_pressure(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1);
double pa_loop_width_position(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1);
double pa_loop_area(pa_arena *pa_mem, pa_arr_float64_1d a0, pa_arr_float64_1d a1);
pa_arr_int64_1d pa_turning_points(pa_arena *pa_mem, pa_arr_float64_1d a0);
