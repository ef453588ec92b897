/*
 * fuzz_replay.c -- main() of a harness built without libFuzzer (gcc, ASan/UBSan): runs
 * LLVMFuzzerTestOneInput once over each file named on the command line. `make ctest-asan`
 * replays the checked-in corpus (c_runtime/fuzz/corpus/<harness>/) this way, so that the
 * inputs the fuzzer found stay guarded without clang.
 */
#include "fuzz.h"

int main(int argc, char **argv)
{
    int i;
    for (i = 1; i < argc; ++i) {
        FILE *f = fopen(argv[i], "rb");
        uint8_t *buf;
        long len;
        if (!f || fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
            fprintf(stderr, "cannot read %s\n", argv[i]);
            return 2;
        }
        buf = (uint8_t *)malloc(len ? (size_t)len : 1);
        if (!buf || fread(buf, 1, (size_t)len, f) != (size_t)len) {
            fprintf(stderr, "cannot read %s\n", argv[i]);
            return 2;
        }
        fclose(f);
        LLVMFuzzerTestOneInput(buf, (size_t)len);
        free(buf);
    }
    printf("replayed %d input%s\n", argc - 1, argc == 2 ? "" : "s");
    return 0;
}
