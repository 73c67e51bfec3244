/*
 * DICOM series (private to src/image/): GDCM behind a small C interface (src/image/dicom_gdcm.cc,
 * the only C++ of the project), the helper program that runs it (src/image/dicom_helper.c:
 * `thorax-dicom`, installed in LIBEXECDIR/thorax/) and the series logic in C (src/image/dicom.c:
 * grouping, sorting, checks, the thx_image). docs/design/image.md, "DICOM" and "The DICOM helper
 * program", give the rules.
 *
 * The C++ side never lets an exception or a GDCM message out: every failure is a return of -1 with
 * a message in `msg` (NUL-terminated, cut to `msgsize`), and GDCM's own warning/error streams are
 * silenced. Debian builds GDCM with its assert()s on, and a truncated or corrupt file trips them
 * (abort): the library therefore never calls GDCM itself. dicom.c starts the helper (posix_spawn,
 * exec: nothing of the caller's signal handlers or allocator hooks follows it) and talks to it over
 * a socket with the protocol below; a helper that dies, hangs or answers garbage is a refusal
 * naming the file.
 */
#ifndef THORAX_IMAGE_DICOM_H
#define THORAX_IMAGE_DICOM_H

#include <stddef.h>

#include "thorax/image/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- The helper's protocol, version THX_DICOM_PROTOCOL. One socket (the helper's fd 3), host byte
 * order (the helper is built with the library, for the same machine), integers u32/i32/u64, doubles
 * IEEE 754 binary64. Strictly request, then reply: the parent never writes while a reply is due, the
 * helper never writes unasked, so neither blocks the other however large a reply.
 *   hello (helper -> parent, once, at start): "THXDICOM" (8 bytes), u32 version
 *   request (parent -> helper): u32 op, u32 rows, u32 columns, u32 path length L (1..1023), L bytes
 *     of path (no NUL); closing the socket asks the helper to exit
 *   reply (helper -> parent): u32 op (the request's), i32 status, u64 payload length, payload:
 *     status -1, either op: the message (1..THX_DICOM_MAX_MESSAGE bytes, no NUL)
 *     SCAN, status 0: not DICOM (payload empty)
 *     SCAN, status 1: the entry's fields in thx_dicom_entry's order but `file` (the parent's own
 *       path): four strings (u16 length, bytes, no NUL, shorter than the field), u32 image,
 *       i32 frames, u32 has_position/has_orientation/has_spacing, 14 doubles (position 3,
 *       orientation 6, pixel_spacing 2, thickness, slope, intercept), u32 rows, u32 columns
 *     PIXELS, status 0: u32 type (THX_DICOM_T_*), u32 rows, u32 columns (the request's), then
 *       rows * columns stored values of that type (column index fastest, before rescale)
 * The parent checks every length against its bound before reading what it announces, every flag,
 * count and type against its range, and that the payload is used up exactly. */
#define THX_DICOM_PROTOCOL 1
#define THX_DICOM_HELLO "THXDICOM"
#define THX_DICOM_OP_SCAN 1u
#define THX_DICOM_OP_PIXELS 2u
#define THX_DICOM_MAX_PATH 1023   /* the longest path in a request (thx_dicom_entry.file holds it) */
#define THX_DICOM_MAX_MESSAGE 2000 /* the longest message in a reply */
#define THX_DICOM_MAX_ENTRY 1024   /* the longest SCAN entry payload (the strings are shorter still) */
enum { THX_DICOM_T_UINT8 = 1, THX_DICOM_T_INT8, THX_DICOM_T_UINT16, THX_DICOM_T_INT16, THX_DICOM_T_UINT32,
       THX_DICOM_T_INT32, THX_DICOM_T_FLOAT32, THX_DICOM_T_FLOAT64 };

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
 * uncompressed, RLE, JPEG, JPEG-LS, JPEG 2000): *data (malloc'ed, the caller frees it) receives the
 * rows * columns stored values (column index fastest, before rescale) as *type (THX_DICOM_T_*),
 * *len their bytes. Returns 0, or -1 with `msg` (not readable, not the size the scan said, colour,
 * several frames, truncated pixel data). */
int thx_dicom_pixels(const char *file, unsigned rows, unsigned columns, void **data, size_t *len, int *type, char *msg,
                     size_t msgsize);

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
