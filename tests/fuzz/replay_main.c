/* Runs a fuzz target over files and directories given on the command line
 * (seed corpora, regression reproducers) without libFuzzer, so any
 * compiler builds it and ctest replays every committed input. Exit 0 when
 * every input ran; 3 when an invariant broke (the input is named on stderr). */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz.h"

static int run_file(const char *path)
{
    FILE *fp = fopen(path, "rb");
    unsigned char *buf;
    long n;
    if (fp == NULL || fseek(fp, 0, SEEK_END) != 0 || (n = ftell(fp)) < 0 || fseek(fp, 0, SEEK_SET) != 0) {
        fprintf(stderr, "replay: cannot read %s\n", path);
        if (fp != NULL) {
            fclose(fp);
        }
        return -1;
    }
    buf = malloc((size_t)n + 1u);
    if (buf == NULL || fread(buf, 1, (size_t)n, fp) != (size_t)n) {
        fprintf(stderr, "replay: cannot read %s\n", path);
        free(buf);
        fclose(fp);
        return -1;
    }
    fclose(fp);
    fprintf(stderr, "replay: %s\n", path);
    (void)LLVMFuzzerTestOneInput(buf, (size_t)n);
    free(buf);
    return 0;
}

static int run_path(const char *path, unsigned *count)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, "replay: no such file or directory: %s\n", path);
        return -1;
    }
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        struct dirent *e;
        int rc = 0;
        if (d == NULL) {
            fprintf(stderr, "replay: cannot open %s\n", path);
            return -1;
        }
        while ((e = readdir(d)) != NULL) {
            char sub[4096];
            if (e->d_name[0] == '.') {
                continue;
            }
            (void)snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            rc |= run_path(sub, count);
        }
        closedir(d);
        return rc;
    }
    ++*count;
    return run_file(path);
}

/* A broken invariant aborts: a plain failure to ctest, so that the
 * reproducers of open findings can be expected to fail (WILL_FAIL). */
static void on_abort(int sig)
{
    (void)sig;
    _exit(3);
}

int main(int argc, char **argv)
{
    unsigned count = 0;
    int i, rc = 0;
    (void)signal(SIGABRT, on_abort);
    for (i = 1; i < argc; ++i) {
        rc |= run_path(argv[i], &count);
    }
    printf("replayed %u inputs\n", count);
    return rc == 0 ? 0 : 1;
}
