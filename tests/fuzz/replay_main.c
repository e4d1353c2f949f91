/*
 * replay_main.c: runs fuzz inputs through a target's LLVMFuzzerTestOneInput without libFuzzer (any compiler):
 *   fuzz_X_replay PATH...     each PATH a file, or a directory whose files (not README*, not dot files) are run
 *                             in name order
 * A violation aborts inside the target (the test fails, naming the input first); prints one line per input and
 * "replayed N inputs" at the end. ctest replays every seed and every past finding with it (tests/fuzz/).
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REPLAY_MAX_FILE (1u << 20) /* inputs are small; larger files are a mistake */
#define REPLAY_MAX_FILES 4096

static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "replay: cannot read %s\n", path);
        return -1;
    }
    uint8_t *buf = malloc(REPLAY_MAX_FILE);
    if (!buf) {
        fclose(f);
        return -1;
    }
    const size_t n = fread(buf, 1, REPLAY_MAX_FILE, f);
    fclose(f);
    /* a copy of exactly n bytes, so that ASan sees reads past the end */
    uint8_t *in = malloc(n ? n : 1);
    if (!in) {
        free(buf);
        return -1;
    }
    memcpy(in, buf, n);
    free(buf);
    fprintf(stderr, "replay: %s (%zu bytes)\n", path, n);
    LLVMFuzzerTestOneInput(in, n);
    free(in);
    return 0;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int run_dir(const char *dir, int *count)
{
    DIR *d = opendir(dir);
    if (!d) {
        fprintf(stderr, "replay: cannot open %s\n", dir);
        return -1;
    }
    char **names = calloc(REPLAY_MAX_FILES, sizeof *names);
    int n = 0;
    struct dirent *e;
    while (names && (e = readdir(d)) != NULL && n < REPLAY_MAX_FILES) {
        if (e->d_name[0] == '.' || strncmp(e->d_name, "README", 6) == 0)
            continue;
        names[n++] = strdup(e->d_name);
    }
    closedir(d);
    if (!names)
        return -1;
    qsort(names, (size_t)n, sizeof *names, cmp_str);
    int rc = 0;
    for (int i = 0; i < n; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        struct stat st;
        if (stat(path, &st) == 0 && S_ISREG(st.st_mode)) {
            if (run_file(path) != 0)
                rc = -1;
            else
                (*count)++;
        }
        free(names[i]);
    }
    free(names);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s FILE|DIR...\n", argv[0]);
        return 2;
    }
    int count = 0, rc = 0;
    for (int i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0) {
            fprintf(stderr, "replay: %s not found\n", argv[i]);
            rc = 1;
        } else if (S_ISDIR(st.st_mode)) {
            if (run_dir(argv[i], &count) != 0)
                rc = 1;
        } else if (run_file(argv[i]) != 0) {
            rc = 1;
        } else {
            count++;
        }
    }
    printf("replayed %d inputs\n", count);
    return rc;
}
