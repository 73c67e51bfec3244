/*
 * DICOM series (private to src/image/): GDCM behind a small C interface (src/image/dicom_gdcm.cc,
 * the only C++ in the library) and the series logic in C (src/image/dicom.c: grouping, sorting,
 * checks, the thx_image). docs/design/image.md, "DICOM", gives the rules.
 *
 * The C++ side never lets an exception or a GDCM message out: every failure is a return of -1 with
 * a message in `msg` (NUL-terminated, cut to `msgsize`), and GDCM's own warning/error streams are
 * silenced (no printing inside the library). Debian builds GDCM with its assert()s on, and a
 * truncated or corrupt file trips them (abort): dicom.c therefore calls these two functions only in
 * a child process (fork), so that a crash inside GDCM becomes an error naming the file.
 */
#ifndef THORAX_IMAGE_DICOM_H
#define THORAX_IMAGE_DICOM_H

#include <stddef.h>

#include "thorax/image/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The tags of one file, as the scan reads them (before any pixel is decoded). */
typedef struct {
    char file[1024];           /* the file's path (folder/name) */
    char series_uid[68];       /* SeriesInstanceUID (0020,000E) */
    char series_number[16];    /* SeriesNumber (0020,0011), "" when absent */
    char description[68];      /* SeriesDescription (0008,103E) */
    char modality[20];         /* Modality (0008,0060) */
    int image;                 /* 1: an image (Rows and Columns present, SOP class an image's or unknown) */
    int frames;                /* NumberOfFrames (0028,0008), 1 when absent */
    int has_position, has_orientation, has_spacing;
    double position[3];        /* ImagePositionPatient (0020,0032), LPS mm */
    double orientation[6];     /* ImageOrientationPatient (0020,0037): row direction, column direction */
    double pixel_spacing[2];   /* PixelSpacing (0028,0030): between rows, between columns (mm) */
    double thickness;          /* SliceThickness (0018,0050), 0 when absent */
    double slope, intercept;   /* RescaleSlope/RescaleIntercept (0028,1053/1052), 1 and 0 when absent */
    unsigned rows, columns;    /* Rows (0028,0010), Columns (0028,0011) */
} thx_dicom_entry;

/* Reads the tags above from one file (up to the pixel data, not decoding it). Returns 1 (DICOM: *e
 * filled), 0 (not DICOM: to be skipped) or -1 with `msg`: a file that says it is DICOM (the "DICM"
 * magic at byte 128, or a name ending in .dcm) and cannot be parsed. */
int thx_dicom_scan_file(const char *file, thx_dicom_entry *e, char *msg, size_t msgsize);

/* Decodes the pixels of one single-frame, single-sample file (any transfer syntax GDCM decodes:
 * uncompressed, RLE, JPEG, JPEG-LS, JPEG 2000) into out[columns*rows] (column index fastest), the
 * stored values before rescale. `type` receives the stored type ("int16", ...), *integer whether it
 * is an integer type. Returns 0, or -1 with `msg` (not readable, not the size the scan said, colour,
 * several frames, truncated pixel data). */
int thx_dicom_pixels(const char *file, unsigned rows, unsigned columns, double *out, char type[16], int *integer,
                     char *msg, size_t msgsize);

/* Whether `path` is a file with the DICOM preamble's "DICM" at byte 128. */
int thx_image_is_dicom_file(const char *path);

/* Reads a DICOM series: `path` a folder (its one series, or `series`: a SeriesInstanceUID or the
 * 1-based number of the listing), or one file of a series (the whole series it belongs to, from its
 * folder). Fills *img in RAS with format "dicom", source_frame "LPS (DICOM patient)" and sha256 (of
 * the sorted slice files' SHA-256 hex digests). */
thx_status thx_image_read_dicom(thx_ctx *ctx, const char *path, const char *series, thx_image *img);

#ifdef __cplusplus
}
#endif

#endif
