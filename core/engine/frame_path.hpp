// Where the largest functions every frame runs through are placed in the program's code.
#pragma once

// Such a function is hot and starts a page of code of its own. Under an emulator (the VM tests run under QEMU's TCG)
// every jump from one page of code to another is looked up in a hash table again after each switch of address space,
// twice a frame, and GCC moves a function's unlikely blocks (which a frame may still run) to its end: a function that
// straddles a page boundary costs a lookup for every jump across it (docs/PERFORMANCE.md, "What the emulator does per
// frame"). On hardware nothing changes but the padding before it.
#if defined(__GNUC__)
#define PH_FRAME_PATH __attribute__((hot, aligned(4096)))
#else
#define PH_FRAME_PATH
#endif
