// tests/core/test_hash.c -- core/rs_hash.h: SHA-256 of buffers and files against the FIPS 180-2
// test vectors (appendix B: "abc", the 448-bit message, one million 'a'), the empty message, and
// a buffer against the same bytes written to a file (1 MiB of random bytes, fixed seed).
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_hash.h"
#include "core/rs_rng.h"
#include "tests/common/rs_test.h"

int main(void)
{
    struct {
        const char *msg;
        const char *hex;
    } v[] = {
        {"", "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"},
        {"abc", "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"},
        {"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq",
         "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"},
    };
    rs_err err = {0};
    char hex[65];
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        CHECK(rs_hash_sha256_buffer(hex, v[i].msg, strlen(v[i].msg), &err) == RS_OK, "%s", err.msg);
        CHECK(strcmp(hex, v[i].hex) == 0, "\"%s\": %s, expected %s", v[i].msg, hex, v[i].hex);
    }
    const size_t n = 1000000;
    char *a = malloc(n);
    memset(a, 'a', n);
    CHECK(rs_hash_sha256_buffer(hex, a, n, &err) == RS_OK, "%s", err.msg);
    CHECK(strcmp(hex, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0") == 0, "a x 1e6: %s", hex);
    free(a);

    // a buffer and a file of the same bytes
    rs_test_seed = 20261128;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    const size_t m = 1 << 20;
    unsigned char *b = malloc(m);
    for (size_t i = 0; i < m; i++) b[i] = (unsigned char)(rs_rng_u64(&rng) >> 56);
    char path[] = "/tmp/roadside-test-hash-XXXXXX";
    FILE *f = fdopen(mkstemp(path), "wb");
    CHECK(f && fwrite(b, 1, m, f) == m && fclose(f) == 0, "cannot write %s", path);
    char hex_file[65];
    long long bytes = 0;
    CHECK(rs_hash_sha256_file(hex_file, &bytes, path, &err) == RS_OK, "%s", err.msg);
    CHECK(rs_hash_sha256_buffer(hex, b, m, &err) == RS_OK, "%s", err.msg);
    CHECK(bytes == (long long)m && strcmp(hex, hex_file) == 0, "file %s (%lld bytes), buffer %s", hex_file, bytes, hex);
    remove(path);
    free(b);
    return rs_test_end("test_hash");
}
