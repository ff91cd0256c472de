// rs_report_doc.c -- the report's document model and its two writers (HTML, PDF). See
// rs_report_doc.h.
#include "report/internal/rs_report_doc.h"

#include <cairo-pdf.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"

// ---- building ----

static char *vformat(const char *fmt, va_list ap)
{
    va_list ap2;
    va_copy(ap2, ap);
    int n = vsnprintf(NULL, 0, fmt, ap2);
    va_end(ap2);
    if (n < 0) return NULL;
    char *s = malloc((size_t)n + 1);
    if (s) vsnprintf(s, (size_t)n + 1, fmt, ap);
    return s;
}

static rs_doc_block *push(rs_doc *doc, rs_doc_kind kind)
{
    if (doc->nomem) return NULL;
    if (doc->N == doc->capacity) {
        int cap = doc->capacity ? 2 * doc->capacity : 32;
        rs_doc_block *b = realloc(doc->blocks, (size_t)cap * sizeof *b);
        if (!b) {
            doc->nomem = true;
            return NULL;
        }
        doc->blocks = b;
        doc->capacity = cap;
    }
    rs_doc_block *b = &doc->blocks[doc->N++];
    memset(b, 0, sizeof *b);
    b->kind = kind;
    return b;
}

#define WITH_TEXT(b, fmt)                  \
    do {                                   \
        va_list ap;                        \
        va_start(ap, fmt);                 \
        (b)->text = vformat(fmt, ap);      \
        va_end(ap);                        \
        if (!(b)->text) doc->nomem = true; \
    } while (0)

void rs_doc_heading(rs_doc *doc, int level, const char *fmt, ...)
{
    rs_doc_block *b = push(doc, RS_DOC_HEADING);
    if (!b) return;
    b->level = level < 1 ? 1 : level > 3 ? 3 : level;
    WITH_TEXT(b, fmt);
}

void rs_doc_paragraph(rs_doc *doc, bool warning, const char *fmt, ...)
{
    rs_doc_block *b = push(doc, RS_DOC_PARAGRAPH);
    if (!b) return;
    b->warning = warning;
    WITH_TEXT(b, fmt);
}

void rs_doc_figure(rs_doc *doc, rs_doc_draw_fn draw, const void *ctx, double aspect, const char *fmt, ...)
{
    rs_doc_block *b = push(doc, RS_DOC_FIGURE);
    if (!b) return;
    b->draw = draw;
    b->ctx = ctx;
    b->aspect = aspect;
    doc->Nfigures++;
    WITH_TEXT(b, fmt);
}

void rs_doc_table(rs_doc *doc, int Ncols)
{
    rs_doc_block *b = push(doc, RS_DOC_TABLE);
    if (b) b->Ncols = Ncols;
}

void rs_doc_cell(rs_doc *doc, const char *fmt, ...)
{
    if (doc->nomem || doc->N == 0 || doc->blocks[doc->N - 1].kind != RS_DOC_TABLE) return;
    rs_doc_block *b = &doc->blocks[doc->N - 1];
    char **cells = realloc(b->cells, (size_t)(b->Ncells + 1) * sizeof *cells);
    if (!cells) {
        doc->nomem = true;
        return;
    }
    b->cells = cells;
    va_list ap;
    va_start(ap, fmt);
    char *s = vformat(fmt, ap);
    va_end(ap);
    if (!s) {
        doc->nomem = true;
        return;
    }
    cells[b->Ncells++] = s;
}

void rs_doc_free(rs_doc *doc)
{
    if (!doc) return;
    for (int i = 0; i < doc->N; i++) {
        rs_doc_block *b = &doc->blocks[i];
        free(b->text);
        for (int k = 0; k < b->Ncells; k++) free(b->cells[k]);
        free(b->cells);
    }
    free(doc->blocks);
    memset(doc, 0, sizeof *doc);
}

// ---- text ----

// Length of the valid UTF-8 sequence starting at s (1..4), 0 when s does not start one.
static int utf8_len(const unsigned char *s)
{
    int n = s[0] < 0x80 ? 1 : (s[0] & 0xE0) == 0xC0 ? 2 : (s[0] & 0xF0) == 0xE0 ? 3 : (s[0] & 0xF8) == 0xF0 ? 4 : 0;
    if (n == 2 && s[0] < 0xC2) return 0; // overlong
    for (int k = 1; k < n; k++)
        if ((s[k] & 0xC0) != 0x80) return 0;
    if (n == 3 && ((s[0] == 0xE0 && s[1] < 0xA0) || (s[0] == 0xED && s[1] >= 0xA0))) return 0; // overlong, surrogate
    if (n == 4 && ((s[0] == 0xF0 && s[1] < 0x90) || s[0] > 0xF4 || (s[0] == 0xF4 && s[1] >= 0x90))) return 0;
    return n;
}

// A copy of s with every byte that does not start a valid UTF-8 sequence replaced by '?'.
// Returns NULL when out of memory.
static char *utf8_clean(const char *s)
{
    size_t n = strlen(s);
    char *d = malloc(n + 1);
    if (!d) return NULL;
    for (size_t i = 0; i < n;) {
        int k = utf8_len((const unsigned char *)s + i);
        if (k == 0) {
            d[i++] = '?';
            continue;
        }
        memcpy(d + i, s + i, (size_t)k);
        i += (size_t)k;
    }
    d[n] = 0;
    return d;
}

void rs_doc_show_text(cairo_t *cr, const char *s)
{
    char *c = utf8_clean(s);
    if (c) cairo_show_text(cr, c);
    free(c);
}

void rs_doc_text_extents(cairo_t *cr, const char *s, cairo_text_extents_t *e)
{
    char *c = utf8_clean(s);
    memset(e, 0, sizeof *e);
    if (c) cairo_text_extents(cr, c, e);
    free(c);
}

// ---- PNG in memory ----

typedef struct {
    unsigned char *data;
    size_t len, cap;
    bool nomem;
} membuf;

static bool membuf_add(membuf *m, const void *data, size_t len)
{
    if (m->nomem) return false;
    if (m->len + len + 1 > m->cap) {
        size_t cap = m->cap ? m->cap : 4096;
        while (cap < m->len + len + 1) cap *= 2;
        unsigned char *d = realloc(m->data, cap);
        if (!d) {
            m->nomem = true;
            return false;
        }
        m->data = d;
        m->cap = cap;
    }
    memcpy(m->data + m->len, data, len);
    m->len += len;
    m->data[m->len] = 0;
    return true;
}

static bool membuf_str(membuf *m, const char *s) { return membuf_add(m, s, strlen(s)); }

static bool membuf_printf(membuf *m, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static bool membuf_printf(membuf *m, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *s = vformat(fmt, ap);
    va_end(ap);
    if (!s) {
        m->nomem = true;
        return false;
    }
    bool ok = membuf_str(m, s);
    free(s);
    return ok;
}

// HTML text: & < > " ' escaped; control characters other than tab and newline dropped.
static void membuf_escaped(membuf *m, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        switch (c) {
        case '&': membuf_str(m, "&amp;"); break;
        case '<': membuf_str(m, "&lt;"); break;
        case '>': membuf_str(m, "&gt;"); break;
        case '"': membuf_str(m, "&quot;"); break;
        case '\'': membuf_str(m, "&#39;"); break;
        default:
            if (c >= 0x80) { // a whole UTF-8 sequence, or '?' for a byte that does not start one
                int k = utf8_len((const unsigned char *)s);
                membuf_add(m, k ? s : "?", k ? (size_t)k : 1);
                s += k ? k - 1 : 0;
            } else if (c >= 0x20 || c == '\t' || c == '\n')
                membuf_add(m, s, 1);
        }
    }
}

// RFC 4648 base64 of len bytes.
static void membuf_base64(membuf *m, const unsigned char *d, size_t len)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < len; i += 3) {
        unsigned v = (unsigned)d[i] << 16;
        if (i + 1 < len) v |= (unsigned)d[i + 1] << 8;
        if (i + 2 < len) v |= d[i + 2];
        char q[4] = {tab[(v >> 18) & 63], tab[(v >> 12) & 63], i + 1 < len ? tab[(v >> 6) & 63] : '=',
                     i + 2 < len ? tab[v & 63] : '='};
        membuf_add(m, q, 4);
    }
}

static cairo_status_t png_write_cb(void *closure, const unsigned char *data, unsigned int length)
{
    return membuf_add(closure, data, length) ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_NO_MEMORY;
}

rs_status rs_doc_png(unsigned char **png, size_t *len, cairo_surface_t *surface, rs_err *err)
{
    membuf m = {0};
    cairo_status_t cs = cairo_surface_write_to_png_stream(surface, png_write_cb, &m);
    if (cs != CAIRO_STATUS_SUCCESS || m.nomem) {
        free(m.data);
        *png = NULL;
        *len = 0;
        if (m.nomem || cs == CAIRO_STATUS_NO_MEMORY) return rs_err_set(err, RS_ERR_NOMEM, "PNG: out of memory");
        return rs_err_set(err, RS_ERR_EXTERNAL, "PNG: cairo: %s", cairo_status_to_string(cs));
    }
    *png = m.data;
    *len = m.len;
    return RS_OK;
}

// ---- HTML ----

static const char html_style[] =
    "body{font-family:sans-serif;max-width:1060px;margin:1em auto;padding:0 1em;color:#222}"
    "h1{border-bottom:2px solid #345}h2{margin-top:2em;border-bottom:1px solid #9ab}"
    "table{border-collapse:collapse;margin:0.5em 0 1em 0;font-size:0.9em}"
    "th,td{border:1px solid #bbb;padding:2px 8px;text-align:right}"
    "th{background:#e4e8ee}td:first-child,th:first-child{text-align:left}"
    "tr:nth-child(even) td{background:#f6f7f9}"
    "figure{margin:1em 0}figure img{max-width:100%;border:1px solid #999}"
    "figcaption{font-size:0.9em;color:#444;font-style:italic}"
    "p.warning{background:#fff3cd;border-left:4px solid #d39e00;padding:4px 8px}";

static rs_status figure_png(membuf *html, const rs_doc_block *b, int width_px, rs_err *err)
{
    int h = (int)(width_px * b->aspect + 0.5);
    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, h);
    cairo_t *cr = cairo_create(s);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    b->draw(cr, width_px, h, b->ctx);
    cairo_status_t cs = cairo_status(cr);
    cairo_destroy(cr);
    if (cs != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(s);
        return rs_err_set(err, RS_ERR_EXTERNAL, "figure '%s': cairo: %s", b->text, cairo_status_to_string(cs));
    }
    unsigned char *png = NULL;
    size_t len = 0;
    rs_status st = rs_doc_png(&png, &len, s, err);
    cairo_surface_destroy(s);
    if (st) return st;
    membuf_printf(html, "<figure><img width=\"%d\" height=\"%d\" alt=\"", width_px, h);
    membuf_escaped(html, b->text);
    membuf_str(html, "\" src=\"data:image/png;base64,");
    membuf_base64(html, png, len);
    membuf_str(html, "\"><figcaption>");
    membuf_escaped(html, b->text);
    membuf_str(html, "</figcaption></figure>\n");
    free(png);
    return RS_OK;
}

rs_status rs_doc_write_html(const rs_doc *doc, const char *title, int figure_width_px, const char *path, rs_err *err)
{
    if (doc->nomem) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    membuf m = {0};
    membuf_str(&m, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>");
    membuf_escaped(&m, title);
    membuf_printf(&m, "</title>\n<style>%s</style></head>\n<body>\n", html_style);
    rs_status st = RS_OK;
    for (int i = 0; i < doc->N && !st; i++) {
        const rs_doc_block *b = &doc->blocks[i];
        switch (b->kind) {
        case RS_DOC_HEADING:
            membuf_printf(&m, "<h%d>", b->level);
            membuf_escaped(&m, b->text);
            membuf_printf(&m, "</h%d>\n", b->level);
            break;
        case RS_DOC_PARAGRAPH:
            membuf_str(&m, b->warning ? "<p class=\"warning\">" : "<p>");
            membuf_escaped(&m, b->text);
            membuf_str(&m, "</p>\n");
            break;
        case RS_DOC_TABLE:
            membuf_str(&m, "<table>\n");
            for (int k = 0; k < b->Ncells; k++) {
                bool head = k < b->Ncols;
                if (k % b->Ncols == 0) membuf_str(&m, "<tr>");
                membuf_str(&m, head ? "<th>" : "<td>");
                membuf_escaped(&m, b->cells[k]);
                membuf_str(&m, head ? "</th>" : "</td>");
                if (k % b->Ncols == b->Ncols - 1 || k == b->Ncells - 1) membuf_str(&m, "</tr>\n");
            }
            membuf_str(&m, "</table>\n");
            break;
        case RS_DOC_FIGURE: st = figure_png(&m, b, figure_width_px, err); break;
        }
    }
    membuf_str(&m, "</body></html>\n");
    if (!st && m.nomem) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    if (!st) st = rs_io_write_file(path, m.data, m.len, err);
    free(m.data);
    return st;
}

// ---- PDF ----

enum { PDF_BODY_PT = 9, PDF_TABLE_PT = 8 };
static const double page_w = 595.276, page_h = 841.89, margin = 42;

typedef struct {
    cairo_t *cr;
    double y; // top of the free space on the current page
    int page;
    const char *title;
} pdf_state;

static void pdf_font(cairo_t *cr, double size, bool bold, bool italic)
{
    cairo_select_font_face(cr, "sans-serif", italic ? CAIRO_FONT_SLANT_ITALIC : CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}

static double text_width(cairo_t *cr, const char *s)
{
    cairo_text_extents_t e;
    rs_doc_text_extents(cr, s, &e);
    return e.x_advance;
}

static void pdf_footer(pdf_state *p)
{
    cairo_t *cr = p->cr;
    pdf_font(cr, 7, false, false);
    cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
    char buf[64];
    snprintf(buf, sizeof buf, "page %d", p->page);
    cairo_move_to(cr, page_w - margin - text_width(cr, buf), page_h - margin / 2);
    rs_doc_show_text(cr, buf);
    cairo_move_to(cr, margin, page_h - margin / 2);
    rs_doc_show_text(cr, p->title);
}

static void pdf_new_page(pdf_state *p)
{
    pdf_footer(p);
    cairo_show_page(p->cr);
    p->page++;
    p->y = margin;
}

// Starts a new page unless `height` fits below p->y.
static void pdf_need(pdf_state *p, double height)
{
    if (p->y + height > page_h - margin && p->y > margin) pdf_new_page(p);
}

// Word-wrapped text across the page width: draws it and advances p->y, or with draw false only
// returns the height it would take (no page break counted).
static double pdf_text_run(pdf_state *p, const char *text, double size, bool bold, bool italic, double indent,
                           bool draw);

static void pdf_text(pdf_state *p, const char *text, double size, bool bold, bool italic, double indent)
{
    pdf_text_run(p, text, size, bold, italic, indent, true);
}

static double pdf_text_run(pdf_state *p, const char *text, double size, bool bold, bool italic, double indent,
                           bool draw)
{
    double height = 0;
    cairo_t *cr = p->cr;
    pdf_font(cr, size, bold, italic);
    double lh = size * 1.35, maxw = page_w - 2 * margin - 2 * indent;
    size_t n = strlen(text);
    char *line = malloc(n + 1);
    if (!line) return 0;
    const char *s = text;
    while (*s) {
        // take words while they fit
        size_t best = 0, k = 0;
        while (true) {
            while (s[k] && s[k] != ' ') k++;
            memcpy(line, s, k);
            line[k] = 0;
            if (best && text_width(cr, line) > maxw) break;
            best = k;
            if (!s[k]) break;
            k++;
        }
        memcpy(line, s, best);
        line[best] = 0;
        if (draw) {
            pdf_need(p, lh);
            pdf_font(cr, size, bold, italic);
            cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
            cairo_move_to(cr, margin + indent, p->y + size);
            rs_doc_show_text(cr, line);
            p->y += lh;
        }
        height += lh;
        s += best;
        while (*s == ' ') s++;
    }
    free(line);
    return height;
}

// Height of what must stay on the page of heading block i (keep-with-next): the paragraphs that
// follow it (a camera's verdict, a table's legend) and the start of the next table (its header
// and two rows) or the whole next figure with its caption, as pdf_write draws them. When that is
// more than half a page, only the heading and two lines of what follows.
static double pdf_figure_height(pdf_state *p, const rs_doc_block *b);
static double pdf_keep_height(pdf_state *p, const rs_doc *doc, int i, double size)
{
    double h = 0;
    int k = i + 1;
    for (; k < doc->N && doc->blocks[k].kind == RS_DOC_PARAGRAPH; k++)
        h += pdf_text_run(p, doc->blocks[k].text, PDF_BODY_PT, false, false, doc->blocks[k].warning ? 8 : 0, false) + 4;
    if (k < doc->N && doc->blocks[k].kind == RS_DOC_TABLE) h += 3 * PDF_TABLE_PT * 1.5;
    if (k < doc->N && doc->blocks[k].kind == RS_DOC_FIGURE) h += pdf_figure_height(p, &doc->blocks[k]);
    if (h > 0.5 * (page_h - 2 * margin)) h = 2 * size;
    return 1.7 * size + h;
}

// Cell text cut to width w with "..." when too long (at a UTF-8 character boundary).
static void pdf_cell(cairo_t *cr, const char *s, double x, double y, double w, bool right)
{
    char buf[256];
    size_t len = strlen(s), n = len < sizeof buf - 4 ? len : sizeof buf - 4;
    bool cut = n < len;
    for (;;) {
        while (n > 0 && ((unsigned char)s[n] & 0xC0) == 0x80) n--;
        memcpy(buf, s, n);
        strcpy(buf + n, cut ? "..." : "");
        if (n == 0 || text_width(cr, buf) <= w) break;
        n--;
        cut = true;
    }
    double tw = text_width(cr, buf);
    cairo_move_to(cr, right ? x + w - tw : x, y);
    rs_doc_show_text(cr, buf);
}

// Cell text word-wrapped to width w: returns the number of lines; draws them (the first line's
// baseline at y, lines lh apart) when draw is true. A word wider than w is cut (pdf_cell).
static int pdf_cell_wrapped(cairo_t *cr, const char *s, double x, double y, double w, double lh, bool right, bool draw)
{
    size_t n = strlen(s);
    char *line = malloc(n + 1);
    if (!line) return 1;
    if (right && text_width(cr, s) > w) right = false; // a wrapped cell reads left to right
    int Nlines = 0;
    while (*s || Nlines == 0) {
        size_t best = 0, k = 0;
        while (true) { // take words while they fit
            while (s[k] && s[k] != ' ') k++;
            memcpy(line, s, k);
            line[k] = 0;
            if (best && text_width(cr, line) > w) break;
            best = k;
            if (!s[k]) break;
            k++;
        }
        memcpy(line, s, best);
        line[best] = 0;
        if (draw) pdf_cell(cr, line, x, y + Nlines * lh, w, right);
        Nlines++;
        s += best;
        while (*s == ' ') s++;
    }
    free(line);
    return Nlines;
}

// Column widths: each column its widest cell, and when the table is wider than the page, the
// narrow columns keep theirs and the wide ones share what is left (their cells wrap).
static void pdf_column_widths(double *w, int nc, double avail)
{
    double total = 0;
    for (int c = 0; c < nc; c++) total += w[c];
    if (total <= avail) return;
    bool *fixed = calloc((size_t)nc, sizeof *fixed);
    if (!fixed) {
        for (int c = 0; c < nc; c++) w[c] *= avail / total;
        return;
    }
    for (bool changed = true; changed;) { // water-filling: columns under the fair share keep their width
        changed = false;
        double left = avail;
        int Nfree = 0;
        for (int c = 0; c < nc; c++) {
            if (fixed[c])
                left -= w[c];
            else
                Nfree++;
        }
        for (int c = 0; c < nc && Nfree; c++)
            if (!fixed[c] && w[c] <= left / Nfree) fixed[c] = changed = true;
        if (!changed)
            for (int c = 0; c < nc; c++)
                if (!fixed[c]) w[c] = left / Nfree;
    }
    free(fixed);
}

// A cell that reads as a number ("12", "-0.5", "1 / 0", "-"): right-aligned, as figures are.
static bool cell_numeric(const char *s)
{
    if (!strcmp(s, "-")) return true;
    if (*s == '-' || *s == '+') s++;
    return *s >= '0' && *s <= '9';
}

static void pdf_table_header(pdf_state *p, const rs_doc_block *b, const double *w, double width, double rh, double lh)
{
    cairo_t *cr = p->cr;
    const int nc = b->Ncols;
    pdf_font(cr, PDF_TABLE_PT, true, false);
    int Nlines = 1;
    for (int c = 0; c < nc && c < b->Ncells; c++) {
        int k = pdf_cell_wrapped(cr, b->cells[c], 0, 0, w[c] - 8, lh, false, false);
        if (k > Nlines) Nlines = k;
    }
    const double h = rh + (Nlines - 1) * lh;
    cairo_set_source_rgb(cr, 0.89, 0.91, 0.93);
    cairo_rectangle(cr, margin, p->y, width, h);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    double x = margin;
    for (int c = 0; c < nc && c < b->Ncells; c++) {
        const bool right = c > 0 && nc + c < b->Ncells && cell_numeric(b->cells[nc + c]); // as its column
        pdf_cell_wrapped(cr, b->cells[c], x + 4, p->y + rh - 3.5, w[c] - 8, lh, right, true);
        x += w[c];
    }
    p->y += h;
}

static void pdf_table(pdf_state *p, const rs_doc_block *b)
{
    cairo_t *cr = p->cr;
    int nc = b->Ncols, nr = (b->Ncells + nc - 1) / nc;
    double *w = calloc((size_t)nc, sizeof *w);
    if (!w) return;
    for (int k = 0; k < b->Ncells; k++) {
        pdf_font(cr, PDF_TABLE_PT, k < nc, false);
        double tw = text_width(cr, b->cells[k]) + 8;
        if (tw > w[k % nc]) w[k % nc] = tw;
    }
    double avail = page_w - 2 * margin, total = 0;
    pdf_column_widths(w, nc, avail);
    for (int c = 0; c < nc; c++) total += w[c];
    const double rh = PDF_TABLE_PT * 1.5, lh = PDF_TABLE_PT * 1.25;
    pdf_table_header(p, b, w, total, rh, lh);
    for (int r = 1; r < nr; r++) {
        pdf_font(cr, PDF_TABLE_PT, false, false);
        int Nlines = 1;
        for (int c = 0; c < nc && r * nc + c < b->Ncells; c++) {
            int k = pdf_cell_wrapped(cr, b->cells[r * nc + c], 0, 0, w[c] - 8, lh, false, false);
            if (k > Nlines) Nlines = k;
        }
        const double h = rh + (Nlines - 1) * lh;
        if (p->y + h > page_h - margin) {
            pdf_new_page(p);
            pdf_table_header(p, b, w, total, rh, lh); // repeated on the new page
        }
        if (r % 2 == 0) {
            cairo_set_source_rgb(cr, 0.965, 0.97, 0.975);
            cairo_rectangle(cr, margin, p->y, total, h);
            cairo_fill(cr);
        }
        pdf_font(cr, PDF_TABLE_PT, false, false);
        cairo_set_source_rgb(cr, 0, 0, 0);
        double x = margin;
        for (int c = 0; c < nc && r * nc + c < b->Ncells; c++) {
            const char *cell = b->cells[r * nc + c];
            pdf_cell_wrapped(cr, cell, x + 4, p->y + rh - 3.5, w[c] - 8, lh, c > 0 && cell_numeric(cell), true);
            x += w[c];
        }
        p->y += h;
    }
    p->y += 8;
    free(w);
}

// The figure as drawn: its size on the page (at most a page high) and its caption's lines.
static void pdf_figure_size(const rs_doc_block *b, double *w_out, double *h_out)
{
    double w = page_w - 2 * margin, h = w * b->aspect;
    double hmax = page_h - 2 * margin - 30;
    if (h > hmax) {
        h = hmax;
        w = h / b->aspect;
    }
    *w_out = w, *h_out = h;
}

// Height of the figure with its caption (they stay together on one page), as pdf_figure draws it.
static double pdf_figure_height(pdf_state *p, const rs_doc_block *b)
{
    double w, h;
    pdf_figure_size(b, &w, &h);
    double cap = pdf_text_run(p, b->text, 8, false, true, 0, false);
    if (h + 4 + cap > page_h - 2 * margin) cap = 0; // a caption too long for the page flows on
    return h + 4 + cap;
}

static void pdf_figure(pdf_state *p, const rs_doc_block *b)
{
    double w, h;
    pdf_figure_size(b, &w, &h);
    pdf_need(p, pdf_figure_height(p, b));
    cairo_t *cr = p->cr;
    cairo_save(cr);
    cairo_translate(cr, margin, p->y);
    cairo_rectangle(cr, 0, 0, w, h);
    cairo_clip(cr);
    b->draw(cr, w, h, b->ctx);
    cairo_restore(cr);
    cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
    cairo_set_line_width(cr, 0.5);
    cairo_rectangle(cr, margin, p->y, w, h);
    cairo_stroke(cr);
    p->y += h + 4;
    pdf_text(p, b->text, 8, false, true, 0);
    p->y += 8;
}

typedef struct {
    rs_io_atomic *a;
    bool failed;
} pdf_sink;

static cairo_status_t pdf_write_cb(void *closure, const unsigned char *data, unsigned int length)
{
    pdf_sink *s = closure;
    if (fwrite(data, 1, length, s->a->f) != length) {
        s->failed = true;
        return CAIRO_STATUS_WRITE_ERROR;
    }
    return CAIRO_STATUS_SUCCESS;
}

rs_status rs_doc_write_pdf(const rs_doc *doc, const char *title, const char *path, rs_err *err)
{
    if (doc->nomem) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    rs_io_atomic a = {0};
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st) return st;
    pdf_sink sink = {&a, false};
    cairo_surface_t *surface = cairo_pdf_surface_create_for_stream(pdf_write_cb, &sink, page_w, page_h);
    char *clean_title = utf8_clean(title);
    if (clean_title) cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_TITLE, clean_title);
    free(clean_title);
    cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_CREATOR, "roadside report");
    cairo_t *cr = cairo_create(surface);
    pdf_state p = {cr, margin, 1, title};
    for (int i = 0; i < doc->N; i++) {
        const rs_doc_block *b = &doc->blocks[i];
        switch (b->kind) {
        case RS_DOC_HEADING: {
            double size = b->level == 1 ? 18 : b->level == 2 ? 14 : 11;
            // no forced page breaks (they left pages a few lines full): a heading starts a new
            // page only when what it keeps with does not fit below it
            pdf_need(&p, pdf_keep_height(&p, doc, i, size));
            p.y += size * 0.4;
            pdf_text(&p, b->text, size, true, false, 0);
            p.y += size * 0.3;
            break;
        }
        case RS_DOC_PARAGRAPH:
            if (b->warning) {
                double y0 = p.y;
                pdf_text(&p, b->text, PDF_BODY_PT, false, false, 8);
                cairo_set_source_rgb(cr, 0.83, 0.62, 0);
                cairo_rectangle(cr, margin, y0, 3, p.y - y0 > 0 ? p.y - y0 : PDF_BODY_PT);
                cairo_fill(cr);
            } else
                pdf_text(&p, b->text, PDF_BODY_PT, false, false, 0);
            p.y += 4;
            break;
        case RS_DOC_TABLE: pdf_table(&p, b); break;
        case RS_DOC_FIGURE: pdf_figure(&p, b); break;
        }
    }
    pdf_footer(&p);
    cairo_status_t cs = cairo_status(cr);
    cairo_destroy(cr);
    cairo_surface_finish(surface);
    if (cs == CAIRO_STATUS_SUCCESS) cs = cairo_surface_status(surface);
    cairo_surface_destroy(surface);
    if (cs != CAIRO_STATUS_SUCCESS || sink.failed) {
        rs_io_atomic_abort(&a);
        if (sink.failed) return rs_err_set(err, RS_ERR_IO, "%s: write failed", path);
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: cairo: %s", path, cairo_status_to_string(cs));
    }
    return rs_io_atomic_commit(&a, err);
}
