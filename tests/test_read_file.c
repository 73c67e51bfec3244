/* thx_read_file (thorax/core/fileio.h): every byte of a file, NUL-terminated, whatever its size and kind: a
 * small file; a large one (at least THX_READ_SPLIT bytes: its two halves read side by side) compared byte for
 * byte, with bytes that differ at the halves' seam; a file whose size the system reports as 0 though it has
 * bytes (/proc); a pipe (no offsets: read as it comes); an empty file; a missing one refused with its name. */
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/fileio.h"

/* the file at path is exactly want (n bytes) when read back */
static int reads_back(thx_ctx *ctx, const char *path, const unsigned char *want, size_t n)
{
    char *text = NULL;
    size_t len = 12345;
    if (thx_read_file(ctx, path, &text, &len) != THX_OK) return 0;
    int ok = len == n && text[n] == '\0' && (n == 0 || memcmp(text, want, n) == 0);
    free(text);
    return ok;
}

int main(void)
{
    if (tl_scratch_make("test_read_file")) return 1;
    thx_ctx *ctx = NULL;
    CHECK(thx_ctx_create(&ctx) == THX_OK);

    /* a small file and an empty one */
    static const unsigned char small[] = "1 2 3\n4 5 6\n";
    tl_write_bytes(tl_path("small.txt"), small, sizeof small - 1);
    CHECK(reads_back(ctx, tl_path("small.txt"), small, sizeof small - 1));
    tl_write_bytes(tl_path("empty.txt"), "", 0);
    CHECK(reads_back(ctx, tl_path("empty.txt"), (const unsigned char *)"", 0));

    /* large files around the split: every byte its own value (a position's hash), odd sizes, so a half put
       at the wrong offset or a byte lost at the seam shows */
    const size_t sizes[] = {THX_READ_SPLIT - 1, THX_READ_SPLIT, THX_READ_SPLIT + 1, 3 * THX_READ_SPLIT + 7};
    unsigned char *big = malloc(sizes[3]);
    CHECK(big != NULL);
    for (size_t i = 0; big && i < sizes[3]; i++) big[i] = (unsigned char)((i * 2654435761u) >> 13);
    for (size_t k = 0; big && k < sizeof sizes / sizeof *sizes; k++) {
        tl_write_bytes(tl_path("big.bin"), big, sizes[k]);
        CHECK(reads_back(ctx, tl_path("big.bin"), big, sizes[k]));
    }

    /* /proc/self/maps: st_size 0, its bytes come all the same (more than the first guess of 64 KB is not
       needed; that it is not empty and ends in a newline is) */
    char *text = NULL;
    size_t len = 0;
    CHECK(thx_read_file(ctx, "/proc/self/maps", &text, &len) == THX_OK && len > 0 && text[len - 1] == '\n');
    free(text);

    /* a pipe: a child writes 3 * THX_READ_SPLIT + 7 bytes into a FIFO, read through it */
    CHECK(mkfifo(tl_path("fifo"), 0600) == 0);
    pid_t pid = fork();
    if (pid == 0) {
        int fd = open(tl_path("fifo"), O_WRONLY);
        size_t done = 0;
        while (fd >= 0 && done < sizes[3]) {
            ssize_t w = write(fd, big + done, sizes[3] - done);
            if (w <= 0) break;
            done += (size_t)w;
        }
        _exit(done == sizes[3] ? 0 : 1);
    }
    CHECK(pid > 0 && reads_back(ctx, tl_path("fifo"), big, sizes[3]));
    int status = 1;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    unlink(tl_path("fifo"));
    free(big);

    /* a missing file: refused, its path in the message */
    text = NULL;
    CHECK(thx_read_file(ctx, tl_path("missing.txt"), &text, &len) == THX_EIO && text == NULL &&
          tl_msg_has(ctx, "missing.txt"));
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_read_file");
}
