/*
 * fdi_status.h - the one status type of the fdi library.
 *
 * Every public function that can fail returns an fdi_status_t. On any status other than FDI_OK the
 * function has not changed the instance it was given (no partial updates), unless its header says so.
 * Cost: none (types only). Memory: none.
 */
#ifndef FDI_STATUS_H
#define FDI_STATUS_H

typedef enum
{
    FDI_OK = 0,         /* success */
    FDI_BAD_ARG = 1,    /* NULL pointer, out-of-range or inconsistent argument / configuration */
    FDI_NOT_FINITE = 2, /* a float input (or a result computed from it) is NaN or +-Inf; state kept */
    FDI_BAD_TABLE = 3,  /* an exported fdi_table_t failed fdi_table_check() */
    FDI_BAD_LAYOUT = 4  /* the caller was compiled with other capacities or struct layouts than the library
                           (fdi_diag_init: e.g. -DFDI_DIAG_MAX_TESTS=24 against a library built with 16) */
} fdi_status_t;

#endif /* FDI_STATUS_H */
