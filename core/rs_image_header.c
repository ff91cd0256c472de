// rs_image_header.c -- an image file's size from its header, without decoding it (rs_image.h):
// PNG through libpng (png_read_info), JPEG through libjpeg (jpeg_read_header). OpenCV has no
// header-only read: cv::imread decodes the whole image before anyone can look at its size.
#include <setjmp.h>
#include <stdbool.h>
#include <stdio.h> // before jpeglib.h, which uses FILE and size_t
#include <string.h>

#include <jpeglib.h>
#include <png.h>

#include "core/rs_image.h"
#include "core/rs_io.h"

// libjpeg's error handler: back to jpeg_size's setjmp instead of exit().
typedef struct {
    struct jpeg_error_mgr mgr;
    jmp_buf back;
} jpeg_trap;

static void jpeg_trap_exit(j_common_ptr cinfo) { longjmp(((jpeg_trap *)cinfo->err)->back, 1); }
static void jpeg_quiet(j_common_ptr cinfo) { (void)cinfo; } // its warnings: not on stderr

// libpng's: errors back to png_size's setjmp, warnings dropped (neither printed on stderr: the
// caller's message says what is wrong with the file)
static void png_trap_error(png_structp png, png_const_charp msg)
{
    (void)msg;
    png_longjmp(png, 1);
}
static void png_quiet(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

static bool jpeg_size(FILE *f, int *width, int *height)
{
    struct jpeg_decompress_struct cinfo;
    jpeg_trap trap;
    cinfo.err = jpeg_std_error(&trap.mgr);
    trap.mgr.error_exit = jpeg_trap_exit;
    trap.mgr.output_message = jpeg_quiet;
    if (setjmp(trap.back)) {
        jpeg_destroy_decompress(&cinfo);
        return false;
    }
    jpeg_create_decompress(&cinfo);
    jpeg_stdio_src(&cinfo, f);
    const bool ok = jpeg_read_header(&cinfo, TRUE) == JPEG_HEADER_OK;
    if (ok) *width = (int)cinfo.image_width, *height = (int)cinfo.image_height;
    jpeg_destroy_decompress(&cinfo);
    return ok;
}

static bool png_size(FILE *f, int *width, int *height)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, png_trap_error, png_quiet);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        png_destroy_read_struct(&png, NULL, NULL);
        return false;
    }
    // libpng refuses more than 1,000,000 columns or rows by default; ours is the caller's bound
    png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        return false;
    }
    png_init_io(png, f);
    png_read_info(png, info);
    *width = (int)png_get_image_width(png, info);
    *height = (int)png_get_image_height(png, info);
    png_destroy_read_struct(&png, &info, NULL);
    return true;
}

rs_status rs_image_size(int *width, int *height, const char *path, rs_err *err)
{
    *width = *height = 0;
    rs_status st = rs_io_check_regular(path, RS_IO_MAX_FILE_BYTES, err);
    if (st) return st;
    FILE *f = fopen(path, "rb");
    if (!f) return rs_err_set(err, RS_ERR_IO, "%s: cannot open", path);
    unsigned char magic[8] = {0};
    const size_t n = fread(magic, 1, sizeof magic, f);
    rewind(f);
    int w = 0, h = 0;
    if (n == 8 && !png_sig_cmp(magic, 0, 8))
        st = png_size(f, &w, &h)
                 ? RS_OK
                 : rs_err_set(err, RS_ERR_PARSE, "%s: cannot read the image: not a readable PNG header", path);
    else if (n >= 3 && magic[0] == 0xff && magic[1] == 0xd8 && magic[2] == 0xff)
        st = jpeg_size(f, &w, &h)
                 ? RS_OK
                 : rs_err_set(err, RS_ERR_PARSE, "%s: cannot read the image: not a readable JPEG header", path);
    else
        st = rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: neither PNG nor JPEG: its size is known only once decoded", path);
    fclose(f);
    if (!st) *width = w, *height = h;
    return st;
}
