// rs_report_doc.h -- a small document model (headings, paragraphs, tables, figures) rendered
// twice from the same blocks: a self-contained HTML file (figures as base64 PNG data URIs,
// inline CSS, no script, no external resource) and a PDF drawn with cairo (figures as vectors
// on cairo's PDF surface, text with cairo's toy font API). Private to report/ (internal).
//
// Every string handed to the document is copied; the HTML writer escapes it (& < > " '), so
// text from input files (site names, landmark ids, notes) can never inject markup.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include <cairo.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Draws a figure of size (w, h) in the user units of cr (pixels for PNG, points for PDF).
// ctx is the pointer given to rs_doc_figure; it must outlive the document's writers.
typedef void (*rs_doc_draw_fn)(cairo_t *cr, double w, double h, const void *ctx);

typedef enum { RS_DOC_HEADING, RS_DOC_PARAGRAPH, RS_DOC_TABLE, RS_DOC_FIGURE } rs_doc_kind;

typedef struct {
    rs_doc_kind kind;
    int level;           // heading level 1..3
    char *text;          // heading / paragraph text, figure caption (owned)
    int Ncells, Ncols;   // table: Ncells cells, Ncols per row; row 0 is the header
    char **cells;        // (Ncells,) owned strings, row-major
    rs_doc_draw_fn draw; // figure
    const void *ctx;
    double aspect; // figure height / width
    bool warning;  // paragraph shown as a warning (coloured box)
} rs_doc_block;

typedef struct {
    rs_doc_block *blocks; // owned, (N,)
    int N, capacity;
    bool nomem; // an allocation failed: the writers refuse the document
    int Nfigures;
} rs_doc;

// Appends blocks. Formatting is printf-style. Allocation failures set doc->nomem.
void rs_doc_heading(rs_doc *doc, int level, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
void rs_doc_paragraph(rs_doc *doc, bool warning, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
void rs_doc_figure(rs_doc *doc, rs_doc_draw_fn draw, const void *ctx, double aspect, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
// Starts a table of Ncols columns; then give its cells row by row (the first row is the header).
void rs_doc_table(rs_doc *doc, int Ncols);
void rs_doc_cell(rs_doc *doc, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

void rs_doc_free(rs_doc *doc); // NULL-safe; frees the blocks, not the figure contexts

// Writes the document as one HTML file to `path` (atomically). Figures are rendered at
// figure_width_px pixels wide. Returns RS_ERR_NOMEM, RS_ERR_IO, RS_ERR_EXTERNAL (cairo).
rs_status rs_doc_write_html(const rs_doc *doc, const char *title, int figure_width_px, const char *path, rs_err *err);

// Writes the document as an A4 PDF to `path` (atomically): blocks flow down the page, a block
// that does not fit starts a new page, tables too long for a page continue on the next with
// their header repeated.
rs_status rs_doc_write_pdf(const rs_doc *doc, const char *title, const char *path, rs_err *err);

// cairo_show_text / cairo_text_extents on text that may not be valid UTF-8 (site files are not
// checked for it): each byte that does not start a valid UTF-8 sequence is shown as '?'.
// Without this a single bad byte puts the cairo context, and so the whole PDF, in error.
void rs_doc_show_text(cairo_t *cr, const char *s);
void rs_doc_text_extents(cairo_t *cr, const char *s, cairo_text_extents_t *e);

// A cairo surface rendered as PNG into memory. *png is malloc'ed (caller frees).
rs_status rs_doc_png(unsigned char **png, size_t *len, cairo_surface_t *surface, rs_err *err);

#ifdef __cplusplus
}
#endif
