// test_io.c -- core/rs_io.h: the one rule for names that become file names (rs_io_name_problem)
// case by case against the rule as written, rs_io_child_path refusing what would leave its folder
// and joining the rest, rs_io_has_extension, and rs_io_remove_stale_temporaries.
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "tests/common/rs_test.h"

int main(void)
{
    static const char *const good[] = {"cam1", "north-east_2", "C.3", "Kamera Süd", "a b", "x", NULL};
    static const struct {
        const char *name, *why;
    } bad[] = {{"", "empty"},
               {"../../escaped", "path separator"},
               {"/abs", "path separator"},
               {"a\\b", "path separator"},
               {"..", "\"..\""},
               {"a..b", "\"..\""},
               {" lead", "blank"},
               {"trail ", "blank"},
               {"new\nline", "control"},
               {"tab\t", "control"},
               {"del\x7f", "control"},
               {"ccccccccccccccccccccccccccccccccccccccccccccccccccccccccccccccccc", "longer than 64"},
               {NULL, NULL}};
    for (int i = 0; good[i]; i++) {
        CHECK(rs_io_name_problem(good[i]) == NULL, "'%s' refused: %s", good[i], rs_io_name_problem(good[i]));
        rs_err err = {0};
        char *p = rs_io_child_path("out/dir", good[i], ".json", &err);
        char want[256];
        snprintf(want, sizeof want, "out/dir/%s.json", good[i]);
        CHECK(p && !strcmp(p, want), "child path of '%s': %s", good[i], p ? p : err.msg);
        free(p);
    }
    CHECK(strlen(bad[11].name) == 65, "the long name is 65 bytes");
    for (int i = 0; bad[i].name; i++) {
        const char *why = rs_io_name_problem(bad[i].name);
        CHECK(why && strstr(why, bad[i].why), "'%s': %s (expected '%s')", bad[i].name, why ? why : "accepted",
              bad[i].why);
        rs_err err = {0};
        char *p = rs_io_child_path("out", bad[i].name, ".json", &err);
        CHECK(!p && err.status == RS_ERR_INVALID && strstr(err.msg, bad[i].why), "child path of '%s': %s", bad[i].name,
              p ? p : err.msg);
        free(p);
    }
    CHECK(rs_io_name_problem(NULL) != NULL, "NULL accepted");
    CHECK(rs_io_has_extension("a/b.YML", "yml") && !rs_io_has_extension("a.yml/b", "yml") &&
              !rs_io_has_extension(".yml", "yml") && !rs_io_has_extension("a.ym", "yml") &&
              rs_io_has_extension("x.cameramodel", "cameramodel"),
          "rs_io_has_extension");
    // only regular files are read, within their bound (issue 14, finding 2)
    char *data = NULL;
    size_t len = 1;
    rs_err err = {0};
    CHECK(rs_io_read_file_max(&data, &len, "/dev/zero", 100, &err) == RS_ERR_IO && !data && len == 0 &&
              strstr(err.msg, "a device"),
          "/dev/zero: %s", err.msg);
    CHECK(rs_io_read_file_max(&data, NULL, "/", 100, &err) == RS_ERR_IO && strstr(err.msg, "a folder"), "/: %s",
          err.msg);
    CHECK(rs_io_check_regular("/dev/null", 100, &err) == RS_ERR_IO, "/dev/null accepted");
    // an output named /dev/null is written into, never renamed over (as root that replaced the
    // device by a regular file); a folder as output is refused
    struct stat sb;
    if (stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode)) {
        CHECK(rs_io_write_file("/dev/null", "x\n", 2, &err) == RS_OK, "write /dev/null: %s", err.msg);
        CHECK(stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode), "/dev/null is no longer a device");
        bool removed = true;
        CHECK(rs_io_remove_if_exists("/dev/null", &removed, &err) == RS_ERR_IO && !removed, "/dev/null removed");
        CHECK(stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode), "/dev/null is gone");
    }
    CHECK(rs_io_write_file("/tmp", "x", 1, &err) == RS_ERR_IO && strstr(err.msg, "is a folder"), "/tmp: %s", err.msg);
    // a killed writer's temporaries are removed, and only they (the synth CI failure of 2026-11-24:
    // a run killed while writing labels left "<file>.tmp.XXXXXX" that the rerun kept)
    char dir[] = "/tmp/rs_test_io_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    static const struct {
        const char *rel;
        bool temporary;
    } files[] = {{"a.json.tmp.Heb7CJ", true},
                 {"sub/b.txt.tmp.000000", true},
                 {"a.json", false},
                 {"c.tmp.Heb7C", false},
                 {"d.tmp.Heb7C-", false},
                 {"e.tmp.Heb7CJK", false},
                 {"sub/.tmp.abcdef", false},
                 {"f.tmp", false},
                 {NULL, false}};
    char path[256];
    snprintf(path, sizeof path, "%s/sub", dir);
    CHECK(mkdir(path, 0777) == 0, "mkdir %s", path);
    int Ntemporary = 0;
    for (int i = 0; files[i].rel; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, files[i].rel);
        CHECK(rs_io_write_file(path, "x", 1, &err) == RS_OK, "%s: %s", path, err.msg);
        Ntemporary += files[i].temporary;
    }
    const size_t Nremoved = rs_io_remove_stale_temporaries(dir);
    CHECK(Nremoved == (size_t)Ntemporary, "%zu temporaries removed, expected %d", Nremoved, Ntemporary);
    for (int i = 0; files[i].rel; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, files[i].rel);
        CHECK((access(path, F_OK) == 0) == !files[i].temporary, "%s: %s", files[i].rel,
              files[i].temporary ? "left" : "removed");
    }
    rs_io_remove_tree(dir);
    return rs_test_end("test_io");
}
