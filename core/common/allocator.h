// How the process's allocator treats large blocks (issue 36, item 1). glibc maps every block above
// its mmap threshold (at most 32 MB, adjusted at run time) straight from the kernel and unmaps it
// when freed, so each scan's arrays and each SIFT pyramid level (a 3000x750 panorama doubled: 36 MB
// a level) were zero-filled page by page again for every scan: 17 % of a first registration of 8
// scans of 3000x750 went to page faults. Blocks up to 64 MB are now reused from the heap, and up to
// 128 MB of free heap top is kept; larger blocks (a whole PTX file read at once) still go back at
// once, and malloc_trim after the features returns the rest.
#pragma once

namespace scanreg {

// Call once at the start of main(), before any thread starts.
void ReuseFreedMemory();

}  // namespace scanreg
