// fuzz_pick_json.c -- libFuzzer harness of the pick API's request bodies (rs_pick_request_parse,
// pick/rs_pick.h: what the server does with every POST body before it looks at a field). Corpus:
// tests/fuzz/corpus/pick_json/.
//
// Held to the header's contract, a breach aborting: a body that parses is a JSON object, the
// bytes hold no NUL, and cJSON prints it back; a failed parse returns no object and says why.
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "fuzz_scratch.h"
#include "pick/rs_pick.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail) { fuzz_breach("fuzz_pick_json", what, detail); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    // the server's body: the bytes received, NUL-terminated after them
    char *body = malloc(size + 1);
    if (!body) breach("out of memory", NULL);
    memcpy(body, data, size);
    body[size] = '\0';
    cJSON *o = NULL;
    rs_err err = {0};
    if (rs_pick_request_parse(&o, body, size, &err) == RS_OK) {
        if (!cJSON_IsObject(o)) breach("a body that parses is not an object", NULL);
        if (memchr(data, '\0', size)) breach("a body with a NUL byte parses", NULL);
        char *back = cJSON_PrintUnformatted(o);
        if (!back) breach("a parsed body does not print", NULL);
        cJSON_free(back);
    } else {
        if (o) breach("a failed parse returned an object", NULL);
        if (!err.msg[0]) breach("a failed parse without a message", NULL);
    }
    cJSON_Delete(o);
    free(body);
    return 0;
}
