/* Scalar and index types of the flight library (switch here, nowhere else). */
#ifndef TSCVX_TYPES_H
#define TSCVX_TYPES_H

/* Floating-point type of all problem data and iterates. */
typedef double tscvx_float;
/* Index type: matrix indices, dimensions, counts (SuiteSparse `int` interface). */
typedef int tscvx_int;

#endif /* TSCVX_TYPES_H */
