/*
 * qemu_ppc_mffs.c -- host tooling of `make check-ppc` (c_runtime/ppc.mk), not flight code:
 * preloaded (qemu-ppc -E LD_PRELOAD=...) into the PowerPC programs run under qemu-user.
 *
 * Debian's 32-bit PowerPC glibc saves and restores the rounding mode in some libm functions
 * (atan2 among them, SET_RESTORE_ROUND) with the ISA 3.0 forms of mffs (mffsl, mffscrni: an
 * mffs with bits 11-15 set). glibc relies on older processors decoding those as a plain
 * mffs (the extra bits were reserved there), as a PowerPC 750 does; qemu 7.2's 750 (and every
 * other 32-bit model) raises an illegal instruction instead. This handler gives them the
 * 750's meaning: FRT := FPSCR (low word), FPSCR unchanged, next instruction. Any other
 * illegal instruction is left to the default action (the program dies as before).
 */
#define _GNU_SOURCE
#include <signal.h>
#include <stdint.h>
#include <string.h>
#include <ucontext.h>

#define PPC_NIP 32 /* gregs index of the instruction address */

static void on_sigill(int sig, siginfo_t *info, void *context)
{
    ucontext_t *uc = (ucontext_t *)context;
    mcontext_t *mc = uc->uc_mcontext.uc_regs;
    const uint32_t insn = *(const uint32_t *)mc->gregs[PPC_NIP];
    (void)info;
    if (insn >> 26 == 63 && ((insn >> 1) & 0x3ffu) == 583u && (insn & 1u) == 0) {
        uint64_t fpscr, v;
        memcpy(&fpscr, &mc->fpregs.fpscr, sizeof fpscr);
        v = 0xfff8000000000000ull | (fpscr & 0xffffffffull);
        memcpy(&mc->fpregs.fpregs[(insn >> 21) & 31u], &v, sizeof v);
        mc->gregs[PPC_NIP] += 4;
        return;
    }
    signal(sig, SIG_DFL); /* not ours: the instruction runs again, unhandled */
}

__attribute__((constructor)) static void install(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_sigill;
    sa.sa_flags = SA_SIGINFO;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGILL, &sa, NULL);
}
