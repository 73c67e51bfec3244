/* GDCM (Debian's libgdcm-dev) behind the C interface of src/image/dicom.h: one file's tags
 * (gdcm::Scanner, up to the pixel data) and one slice's pixels (gdcm::ImageReader, which
 * decodes the compressed transfer syntaxes with GDCM's own codecs). The only C++ of the project,
 * linked into the helper program thorax-dicom (src/image/dicom_helper.c), not into the library:
 * no exception crosses the extern "C" boundary, and GDCM's warning and error streams are
 * silenced (our messages say what failed). */
#include "image/dicom.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>


#include <gdcmDataSet.h>
#include <gdcmDirectory.h>
#include <gdcmExplicitDataElement.h>
#include <gdcmFileMetaInformation.h>
#include <gdcmImplicitDataElement.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmMediaStorage.h>
#include <gdcmPixelFormat.h>
#include <gdcmScanner.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>

namespace {

void say(char *msg, size_t size, const std::string &text)
{
    if (size == 0) return;
    std::snprintf(msg, size, "%s", text.c_str());
}

/* GDCM writes its warnings and errors to std::cerr unless told otherwise: into a sink. */
void quiet()
{
    static std::ostringstream sink;
    gdcm::Trace::SetDebug(false);
    gdcm::Trace::SetWarning(false);
    gdcm::Trace::SetError(false);
    gdcm::Trace::SetStream(sink);
    sink.str("");
}

std::string trim(const char *s)
{
    if (!s) return std::string();
    std::string t(s);
    size_t b = t.find_first_not_of(" \t\r\n");
    size_t e = t.find_last_not_of(std::string(" \t\r\n\0", 5));
    if (b == std::string::npos || e == std::string::npos) return std::string();
    return t.substr(b, e - b + 1);
}

void copy(char *dst, size_t size, const std::string &s) { std::snprintf(dst, size, "%s", s.c_str()); }

/* A decimal string (DS) value with `want` components separated by '\'; false when absent or malformed. */
bool numbers(const char *s, double *out, int want)
{
    std::string t = trim(s);
    if (t.empty()) return false;
    const char *p = t.c_str();
    for (int k = 0; k < want; k++) {
        char *end = nullptr;
        double v = std::strtod(p, &end);
        if (end == p || !std::isfinite(v)) return false;
        out[k] = v;
        while (*end == ' ') end++;
        if (k + 1 < want) {
            if (*end != '\\') return false;
            p = end + 1;
        } else if (*end != '\0') {
            return false;
        }
    }
    return true;
}

bool has_dicm(const std::string &path)
{
    FILE *f = std::fopen(path.c_str(), "rb");
    if (!f) return false;
    char b[132];
    size_t n = std::fread(b, 1, sizeof b, f);
    std::fclose(f);
    return n == sizeof b && std::memcmp(b + 128, "DICM", 4) == 0;
}

bool ends_dcm(const std::string &path)
{
    if (path.size() < 4) return false;
    std::string e = path.substr(path.size() - 4);
    for (char &c : e) c = (char)std::tolower((unsigned char)c);
    return e == ".dcm";
}

const gdcm::Tag T_SERIES_UID(0x0020, 0x000e), T_SERIES_NUMBER(0x0020, 0x0011), T_DESCRIPTION(0x0008, 0x103e),
    T_MODALITY(0x0008, 0x0060), T_POSITION(0x0020, 0x0032), T_ORIENTATION(0x0020, 0x0037),
    T_SPACING(0x0028, 0x0030), T_ROWS(0x0028, 0x0010), T_COLUMNS(0x0028, 0x0011), T_SLOPE(0x0028, 0x1053),
    T_INTERCEPT(0x0028, 0x1052), T_SOP_CLASS(0x0008, 0x0016), T_FRAMES(0x0028, 0x0008),
    T_THICKNESS(0x0018, 0x0050);

/* One file's tags: 1 (DICOM, *e filled), 0 (not DICOM: skipped), -1 (says it is DICOM, cannot be parsed). */
int scan_file(const char *file, thx_dicom_entry *e, char *msg, size_t msgsize)
{
    quiet();
    std::string f(file);
    gdcm::Scanner s;
    const gdcm::Tag tags[] = {T_SERIES_UID, T_SERIES_NUMBER, T_DESCRIPTION, T_MODALITY, T_POSITION,
                              T_ORIENTATION, T_SPACING, T_ROWS, T_COLUMNS, T_SLOPE, T_INTERCEPT,
                              T_SOP_CLASS, T_FRAMES, T_THICKNESS};
    for (const gdcm::Tag &t : tags) s.AddTag(t);
    gdcm::Directory::FilenamesType one(1, f);
    if (!s.Scan(one) || !s.IsKey(file)) {
        if (has_dicm(f) || ends_dcm(f)) {
            say(msg, msgsize, f + ": " + (has_dicm(f) ? "has the DICOM preamble" : "is named .dcm") +
                                  " but cannot be parsed as DICOM (truncated or corrupt)");
            return -1;
        }
        return 0;
    }
    std::memset(e, 0, sizeof *e);
    copy(e->file, sizeof e->file, f);
    copy(e->series_uid, sizeof e->series_uid, trim(s.GetValue(file, T_SERIES_UID)));
    copy(e->series_number, sizeof e->series_number, trim(s.GetValue(file, T_SERIES_NUMBER)));
    copy(e->description, sizeof e->description, trim(s.GetValue(file, T_DESCRIPTION)));
    copy(e->modality, sizeof e->modality, trim(s.GetValue(file, T_MODALITY)));
    double v[6];
    e->rows = numbers(s.GetValue(file, T_ROWS), v, 1) && v[0] >= 1 && v[0] <= 65535 ? (unsigned)v[0] : 0;
    e->columns = numbers(s.GetValue(file, T_COLUMNS), v, 1) && v[0] >= 1 && v[0] <= 65535 ? (unsigned)v[0] : 0;
    std::string sop = trim(s.GetValue(file, T_SOP_CLASS));
    gdcm::MediaStorage::MSType ms = gdcm::MediaStorage::GetMSType(sop.c_str());
    bool known_not_image = ms != gdcm::MediaStorage::MS_END && !gdcm::MediaStorage::IsImage(ms);
    e->image = e->rows > 0 && e->columns > 0 && !known_not_image;
    e->frames = numbers(s.GetValue(file, T_FRAMES), v, 1) ? (int)std::max(1.0, std::min(v[0], 1e9)) : 1;
    e->has_position = numbers(s.GetValue(file, T_POSITION), e->position, 3);
    e->has_orientation = numbers(s.GetValue(file, T_ORIENTATION), e->orientation, 6);
    e->has_spacing = numbers(s.GetValue(file, T_SPACING), e->pixel_spacing, 2);
    e->thickness = numbers(s.GetValue(file, T_THICKNESS), v, 1) ? v[0] : 0;
    e->slope = numbers(s.GetValue(file, T_SLOPE), v, 1) ? v[0] : 1;
    e->intercept = numbers(s.GetValue(file, T_INTERCEPT), v, 1) ? v[0] : 0;
    return 1;
}

int pixels(const char *file, unsigned rows, unsigned columns, void **data, size_t *datalen, int *type, char *msg,
           size_t msgsize)
{
    quiet();
    std::string f(file);
    gdcm::ImageReader r;
    r.SetFileName(file);
    if (!r.Read()) {
        say(msg, msgsize, f + ": the image cannot be read (truncated or corrupt pixel data, or a form GDCM does not decode)");
        return -1;
    }
    /* GDCM pads a value cut short by the end of the file ("Incomplete Pixel Data", a warning only):
     * the elements' encoded length against the file's size says whether it was all there */
    {
        const gdcm::File &ff = r.GetFile();
        const gdcm::FileMetaInformation &h = ff.GetHeader();
        const gdcm::DataSet &ds = ff.GetDataSet();
        unsigned long long want = (unsigned long long)h.GetFullLength() +
                                  (h.GetDataSetTransferSyntax().IsImplicit()
                                       ? (unsigned long long)ds.GetLength<gdcm::ImplicitDataElement>()
                                       : (unsigned long long)ds.GetLength<gdcm::ExplicitDataElement>());
        struct stat sb;
        if (stat(file, &sb) == 0 && (unsigned long long)sb.st_size < want) {
            say(msg, msgsize, f + ": the file holds " + std::to_string((long long)sb.st_size) + " bytes, its elements need " +
                                  std::to_string(want) + ": truncated");
            return -1;
        }
    }
    const gdcm::Image &im = r.GetImage();
    const unsigned *dims = im.GetDimensions();
    unsigned nd = im.GetNumberOfDimensions();
    if (nd == 3 && dims[2] > 1) {
        say(msg, msgsize, f + ": " + std::to_string(dims[2]) + " frames in one file (a multi-frame image): thorax reads "
                                                             "series of single-frame slices");
        return -1;
    }
    if (dims[0] != columns || dims[1] != rows) {
        say(msg, msgsize, f + ": the pixel data are " + std::to_string(dims[1]) + " x " + std::to_string(dims[0]) +
                              " (rows x columns), the header said " + std::to_string(rows) + " x " +
                              std::to_string(columns));
        return -1;
    }
    const gdcm::PixelFormat &pf = im.GetPixelFormat();
    if (pf.GetSamplesPerPixel() != 1) {
        say(msg, msgsize, f + ": " + std::to_string(pf.GetSamplesPerPixel()) +
                              " samples per pixel (a colour image): thorax reads grey-level slices");
        return -1;
    }
    const gdcm::PhotometricInterpretation &pi = im.GetPhotometricInterpretation();
    if (pi != gdcm::PhotometricInterpretation::MONOCHROME1 && pi != gdcm::PhotometricInterpretation::MONOCHROME2) {
        say(msg, msgsize, f + ": photometric interpretation " + std::string(gdcm::PhotometricInterpretation::GetPIString(pi)) +
                              ": thorax reads MONOCHROME1/2 slices");
        return -1;
    }
    size_t n = (size_t)rows * columns;
    const char *name = nullptr;
    size_t bytes = 0;
    int code = 0;
    switch (pf.GetScalarType()) {
    case gdcm::PixelFormat::UINT8: name = "uint8", bytes = 1, code = THX_DICOM_T_UINT8; break;
    case gdcm::PixelFormat::INT8: name = "int8", bytes = 1, code = THX_DICOM_T_INT8; break;
    case gdcm::PixelFormat::UINT16: name = "uint16", bytes = 2, code = THX_DICOM_T_UINT16; break;
    case gdcm::PixelFormat::INT16: name = "int16", bytes = 2, code = THX_DICOM_T_INT16; break;
    case gdcm::PixelFormat::UINT32: name = "uint32", bytes = 4, code = THX_DICOM_T_UINT32; break;
    case gdcm::PixelFormat::INT32: name = "int32", bytes = 4, code = THX_DICOM_T_INT32; break;
    case gdcm::PixelFormat::FLOAT32: name = "float32", bytes = 4, code = THX_DICOM_T_FLOAT32; break;
    case gdcm::PixelFormat::FLOAT64: name = "float64", bytes = 8, code = THX_DICOM_T_FLOAT64; break;
    default:
        say(msg, msgsize, f + ": pixel format " + std::string(pf.GetScalarTypeAsString()) + " is not one thorax reads");
        return -1;
    }
    size_t len = im.GetBufferLength();
    if (len != n * bytes) {
        say(msg, msgsize, f + ": the decoded pixel data hold " + std::to_string(len) + " bytes, " + std::to_string(n) +
                              " " + name + " pixels need " + std::to_string(n * bytes));
        return -1;
    }
    void *buf = std::malloc(len ? len : 1);
    if (!buf) {
        say(msg, msgsize, f + ": out of memory for " + std::to_string(len) + " bytes of pixels");
        return -1;
    }
    if (!im.GetBuffer((char *)buf)) {
        std::free(buf);
        say(msg, msgsize, f + ": the pixel data cannot be decoded (truncated or corrupt)");
        return -1;
    }
    *data = buf;
    *datalen = len;
    *type = code;
    return 0;
}

} // namespace

extern "C" int thx_dicom_scan_file(const char *file, thx_dicom_entry *e, char *msg, size_t msgsize)
{
    try {
        return scan_file(file, e, msg, msgsize);
    } catch (const std::exception &x) {
        say(msg, msgsize, std::string(file) + ": GDCM failed while reading its tags: " + x.what());
    } catch (...) {
        say(msg, msgsize, std::string(file) + ": GDCM failed while reading its tags");
    }
    return -1;
}

extern "C" int thx_dicom_pixels(const char *file, unsigned rows, unsigned columns, void **data, size_t *len, int *type,
                                char *msg, size_t msgsize)
{
    *data = nullptr;
    *len = 0;
    try {
        return pixels(file, rows, columns, data, len, type, msg, msgsize);
    } catch (const std::bad_alloc &) {
        say(msg, msgsize, std::string(file) + ": GDCM ran out of memory while decoding the pixels");
    } catch (const std::exception &e) {
        say(msg, msgsize, std::string(file) + ": GDCM failed while decoding the pixels: " + e.what());
    } catch (...) {
        say(msg, msgsize, std::string(file) + ": GDCM failed while decoding the pixels");
    }
    return -1;
}
