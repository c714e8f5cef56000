#pragma once
// Large models spend much of their set-up in page faults: a million-body run touches
// gigabytes a 4 KiB page at a time, and on a virtual machine each fault is dear (a
// fifth of a 200 000-body start on the 2-core VM). Two glibc malloc tunables help:
// glibc.malloc.hugetlb=1 asks the kernel for transparent huge pages, and a high
// glibc.malloc.mmap_threshold keeps large blocks (a state vector of a million bodies is
// 100 MB) in the heap, so a freed one is reused rather than unmapped and zeroed afresh
// when the next is made. Together they halve a 300 000-body start (3.9 s -> 1.8 s on the
// 2-core VM, `mbsflow run c300k.json --t-end 1e-9`). A third, glibc.malloc.trim_threshold
// = 256 MiB, keeps freed memory at the top of the heap instead of giving it back and
// faulting in (and zeroing) a fresh huge page when the heap grows again, which the
// default 128 KiB did at every step of an implicit run: a tirk run of the 2000-body chain
// took 0.285-0.293 s on 2 threads and 0.187-0.247 s on 1 with it, 0.201-0.205 s and
// 0.185-0.187 s without; CVODE in the same runs 0.207-0.214 s either way (`bench stiff
// --problems chain --frequencies 1e4 --tolerances 1e-3`, alternated four times). Tunables are read only when a
// process starts, so mbsflow starts itself once more with them set.
//
// That second start costs 16-18 ms (`mbsflow --version` 33-36 ms against 17-19 ms; IFToMM
// A05 with tirk at 1e-4, the whole process 115-127 ms against 104-108 ms), and small models gain
// nothing from huge pages (a 2000-link chain's run within noise; the 10 000-link chain's 10
// modes 2.2-2.4 s with them, 1.9 s without). So mbsflow restarts only for commands that make
// or receive models of unknown size (generate, bench, worker) and for a command line that
// names a file of at least 16 MiB (a model of some 35 000 bodies or more).
// MBSFLOW_HUGE_PAGES=1 restarts always, =0 never; nothing happens where the kernel never
// gives huge pages, where GLIBC_TUNABLES already names glibc.malloc.hugetlb, or under
// valgrind.
//
// The same restart sets OPENBLAS_THREAD_TIMEOUT=22 unless it is set: OpenBLAS (loaded for
// the modes' and the reductions' dense products) starts its threads as it is loaded, and
// each spins for 2^28 cycles (about 0.1 s) before it sleeps, in every mbsflow process,
// whether it calls BLAS or not. On the 2-core VM that spinner took a core from the run and
// its results writer: 5 % of the CPU samples of IFToMM A02 with a results file (`perf
// record mbsflow run examples/models/iftomm_a02_n_four_bar.json -o a02.h5`), none with
// 2^22 cycles (about 1.4 ms), which still keeps the threads awake between the calls of a
// product.

namespace mbsflow::cli {

// Replaces the process by itself with the tunable set, or returns (when off, not worth it
// for this command line, already set, or exec failed).
void restart_with_huge_pages(char** argv);

// Whether this process's malloc was started with glibc.malloc.hugetlb set to 1 or 2.
bool huge_pages_on();

// Gives the memory that malloc holds free back to the kernel (malloc_trim), huge pages or
// not. Reading and cutting a large model free hundreds of MB on the main thread in
// scattered chunks, and the submodels are then built on worker threads, whose allocations
// come from other malloc arenas and cannot reuse them; building them frees the copies of
// their joints, which the first evaluation does not all reuse. A 1000 x 1000 grid's
// resident memory after the cut fell from 1126 to 705 MB, and with the memory given back
// after each phase of the run too, its peak from 1.97 to 1.78 GiB (notes/parallel-measurements.md).
void give_back_free_memory();

}  // namespace mbsflow::cli
