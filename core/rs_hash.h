// rs_hash.h -- the SHA-256 of a file (OpenSSL's EVP, libcrypto): what the report lists for its
// inputs, what a dataset records of the camera models it was made with and eval checks. A
// library of its own (core_hash_dep in core/meson.build), so that only the rooms that call it
// link libcrypto.
#pragma once
#include <stddef.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// SHA-256 of the file at path, streamed (64 KiB at a time), as 64 lower-case hex digits in hex
// (65 bytes with the NUL; `sha256sum FILE` prints the same). *bytes (may be NULL): the file's
// size. Errors: RS_ERR_IO (cannot open or read, naming the file), RS_ERR_EXTERNAL (OpenSSL).
rs_status rs_hash_sha256_file( // out
    char hex[65], long long *bytes,
    // in
    const char *path, rs_err *err);

// SHA-256 of n bytes at data (NULL allowed when n == 0), as rs_hash_sha256_file gives it:
// `printf ... | sha256sum` prints the same. Errors: RS_ERR_EXTERNAL (OpenSSL).
rs_status rs_hash_sha256_buffer( // out
    char hex[65],
    // in
    const void *data, size_t n, rs_err *err);

#ifdef __cplusplus
}
#endif
