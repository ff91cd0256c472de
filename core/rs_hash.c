// rs_hash.c -- the SHA-256 of a file or a buffer through OpenSSL's EVP interface (core/rs_hash.h).
#include "core/rs_hash.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include <openssl/evp.h>

// The digest of md as 64 hex digits; frees md. false when OpenSSL failed.
static bool finish(char hex[65], EVP_MD_CTX *md, bool ok)
{
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    ok = ok && EVP_DigestFinal_ex(md, digest, &len) == 1 && len == 32;
    for (unsigned i = 0; ok && i < len; i++) snprintf(hex + 2 * i, 3, "%02x", digest[i]);
    EVP_MD_CTX_free(md);
    return ok;
}

rs_status rs_hash_sha256_buffer(char hex[65], const void *data, size_t n, rs_err *err)
{
    EVP_MD_CTX *md = EVP_MD_CTX_new();
    const bool ok =
        md && EVP_DigestInit_ex(md, EVP_sha256(), NULL) == 1 && (n == 0 || EVP_DigestUpdate(md, data, n) == 1);
    if (!finish(hex, md, ok)) return rs_err_set(err, RS_ERR_EXTERNAL, "SHA-256 failed (OpenSSL)");
    return RS_OK;
}

rs_status rs_hash_sha256_file(char hex[65], long long *bytes, const char *path, rs_err *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return rs_err_set(err, RS_ERR_IO, "%s: %s", path, strerror(errno));
    EVP_MD_CTX *md = EVP_MD_CTX_new();
    bool ok = md && EVP_DigestInit_ex(md, EVP_sha256(), NULL) == 1;
    unsigned char buf[65536];
    size_t n;
    long long total = 0;
    while (ok && (n = fread(buf, 1, sizeof buf, f)) > 0) {
        ok = EVP_DigestUpdate(md, buf, n) == 1;
        total += (long long)n;
    }
    const bool read_error = ferror(f) != 0;
    ok = finish(hex, md, ok && !read_error);
    fclose(f);
    if (read_error) return rs_err_set(err, RS_ERR_IO, "%s: read error", path);
    if (!ok) return rs_err_set(err, RS_ERR_EXTERNAL, "%s: SHA-256 failed (OpenSSL)", path);
    if (bytes) *bytes = total;
    return RS_OK;
}
