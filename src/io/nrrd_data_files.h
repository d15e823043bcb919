/* Where a NRRD's data lives: the files its header names, as Teem 1.12
 * names them (nrrd_data_files.c). */
#ifndef VS_NRRD_DATA_FILES_H
#define VS_NRRD_DATA_FILES_H

#include <stddef.h>

#include <teem/nrrd.h>

/* How many data files: a template's numbers, a list's names, else 1
 * (one detached file, or the data after the header). */
unsigned vs_nrrd_data_count(const NrrdIoState *nio);

/* The path of detached data file i (header-relative names joined to the
 * header's folder); 0 if the data follows the header or the path does not
 * fit in cap bytes. */
int vs_nrrd_data_path(const NrrdIoState *nio, unsigned i, char *buf, size_t cap);

#endif
