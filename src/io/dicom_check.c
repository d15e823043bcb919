/* GDCM allocates an element's value from the length the file states before
 * it reads it: an 870-byte file whose element claims 4 GB made the parsing
 * child touch 4 GB (found by tests/fuzz/fuzz_dicom.c).  This walks the
 * elements as one stream (file meta, then the data set in its transfer
 * syntax; a sequence or encapsulated pixel data of undefined length is
 * walked into, its items and fragments too) and refuses a defined length
 * that runs past the end of the file.  A big-endian data set is walked in
 * its byte order: GDCM, failing to read one, retries it little-endian with
 * VRs guessed, where a misread length allocated 2.9 GB for a 513-byte file
 * (fuzz_dicom), so a file must be sound in the syntax it declares.
 * Deflated data sets end the walk, leaving them to GDCM.  Only lengths are
 * checked, so no file GDCM reads correctly is refused. */
#include "dicom_check.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* Value representations whose length field is 4 bytes after 2 reserved ones
 * (explicit VR); the others have a 2-byte length. */
static int long_vr(const unsigned char vr[2])
{
    static const char *const v[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ", "SV", "UC", "UN", "UR", "UT", "UV"};
    for (size_t i = 0; i < sizeof v / sizeof *v; i++)
        if (vr[0] == (unsigned char)v[i][0] && vr[1] == (unsigned char)v[i][1]) return 1;
    return 0;
}
static int known_vr(const unsigned char vr[2])
{
    static const char *const v[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FD", "FL", "IS", "LO", "LT", "PN",
                                    "SH", "SL", "SS", "ST", "TM", "UI", "UL", "US"};
    if (long_vr(vr)) return 1;
    for (size_t i = 0; i < sizeof v / sizeof *v; i++)
        if (vr[0] == (unsigned char)v[i][0] && vr[1] == (unsigned char)v[i][1]) return 1;
    return 0;
}

vs_status vs_dicom_check(vs_context *ctx, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat sb;
    if (fstat(fileno(f), &sb) != 0) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
    }
    const uint64_t size = (uint64_t)sb.st_size;
    unsigned char b[132];
    uint64_t pos = 0;
    if (fread(b, 1, sizeof b, f) == sizeof b && !memcmp(b + 128, "DICM", 4)) pos = 132;
    int in_meta = 1, explicit_vr = -1; /* -1: the data set's VR rule not known yet */
    int be = 0;                        /* the data set is big-endian */
    int encapsulated = 0;              /* inside pixel data of undefined length */
    unsigned depth = 0;                /* open sequences (and pixel data) of undefined length */
    vs_status st = VS_OK;
    char ts[65] = "";
    while (st == VS_OK && pos + 8 <= size) {
        unsigned char e[12];
        if (fseeko(f, (off_t)pos, SEEK_SET) != 0 || fread(e, 1, 8, f) != 8) break;
        if (in_meta && (e[0] | e[1] << 8u) != 0x0002) {
            in_meta = 0;
            /* the meta group names the data set's syntax; without one, the
             * first element tells (as vs_dicom_sniff does) */
            if (!strcmp(ts, "1.2.840.10008.1.2")) explicit_vr = 0;
            else if (!strcmp(ts, "1.2.840.10008.1.2.2")) explicit_vr = 1, be = 1;
            else if (!strcmp(ts, "1.2.840.10008.1.2.1.99")) break; /* deflated: left to GDCM */
            else if (ts[0]) explicit_vr = 1;
        }
#define U16(p) (be ? (unsigned)(p)[0] << 8u | (p)[1] : (unsigned)(p)[0] | (p)[1] << 8u)
#define U32(p) (be ? (uint64_t)(p)[0] << 24u | (uint64_t)(p)[1] << 16u | (p)[2] << 8u | (p)[3] \
                   : (p)[0] | (p)[1] << 8u | (uint64_t)(p)[2] << 16u | (uint64_t)(p)[3] << 24u)
        const unsigned group = U16(e), elem = U16(e + 2);
        /* items and delimiters (group FFFE) have no VR in any syntax */
        const int ex = group != 0xFFFEu && (in_meta || (explicit_vr < 0 ? known_vr(e + 4) : explicit_vr));
        /* GDCM reads an unknown VR of a little-endian data set as implicit
         * (as below); in a big-endian one it gives up and rereads the file
         * little-endian, misreading lengths (4 GB for a 639-byte file) */
        if (be && ex && !known_vr(e + 4)) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: malformed DICOM: element (%04x,%04x) of a big-endian data set has no valid VR",
                              path, group, elem);
            break;
        }
        if (!in_meta && explicit_vr < 0) explicit_vr = ex;
        uint64_t len, head = 8;
        if (ex && known_vr(e + 4) && !long_vr(e + 4)) {
            len = U16(e + 6);
        } else if (ex && known_vr(e + 4)) {
            if (fread(e + 8, 1, 4, f) != 4) break;
            len = U32(e + 8);
            head = 12;
        } else { /* implicit VR, or an unknown VR read as GDCM falls back */
            len = U32(e + 4);
        }
#undef U16
#undef U32
        /* encapsulated pixel data holds items and its delimiter only: GDCM,
         * meeting anything else, rereads the file with VRs guessed and took
         * 4 GB for a 1274-byte one (fuzz_dicom) */
        if (encapsulated && group != 0xFFFEu) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: malformed DICOM: encapsulated pixel data holds element (%04x,%04x), not an item",
                              path, group, elem);
            break;
        }
        /* command elements (group 0000) belong to network messages, never
         * to a file (PS3.10): a file that starts with them is not DICOM.
         * GDCM, given one whose "DICM" sat a byte off its place, read it
         * with VRs guessed and took over 2 GB for 1203 bytes (fuzz_dicom) */
        if (group == 0x0000u) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: malformed DICOM: command element (0000,%04x) in a file", path,
                              elem);
            break;
        }
        /* an item belongs in a sequence: GDCM, meeting one in the data set
         * itself, rereads the file with VRs guessed and took 4 GB for a
         * 1194-byte one (fuzz_dicom) */
        if (group == 0xFFFEu && elem == 0xE000u && depth == 0) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: malformed DICOM: an item outside any sequence", path);
            break;
        }
        if (group == 0xFFFEu && elem == 0xE0DDu) {
            encapsulated = 0;
            if (depth) depth--;
        }
        if (len == 0xFFFFFFFFu || (group == 0xFFFEu && elem != 0xE000u)) {
            if (group == 0x7FE0u && elem == 0x0010u) encapsulated = 1;
            if (group != 0xFFFEu) depth++;
            pos += head; /* undefined length: its items follow; delimiters: nothing */
            continue;
        }
        if (len > size - pos - head) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: malformed DICOM: element (%04x,%04x) claims %llu bytes, the file has %llu left", path,
                              group, elem, (unsigned long long)len, (unsigned long long)(size - pos - head));
            break;
        }
        if (in_meta && group == 0x0002 && elem == 0x0010 && len < sizeof ts) {
            if (fread(ts, 1, (size_t)len, f) != len) break;
            ts[len] = '\0';
            for (size_t i = strlen(ts); i > 0 && (ts[i - 1] == ' ' || ts[i - 1] == '\0'); i--) ts[i - 1] = '\0';
        }
        pos += head + len;
    }
    fclose(f);
    return st;
}
