#pragma once
// A results file whose writer was killed while it closed the file (Hdf5Sink::end() adds
// the coupling records and the XDMF views outside SWMR mode, then closes): HDF5 had
// written the superblock with the file's new end but not yet grown the file to it, and
// it refuses to open a file shorter than its stored end ("truncated file").
#include <string>

namespace mbsflow {

// Grows such a file with zeros to its stored end, so that HDF5 opens it; returns whether
// it did. Safe for a resumed run: what a checkpoint counts was flushed before the
// checkpoint was taken, so it lies below the size the file had then, which is at most
// its size now; the bytes added are of what the killed writer made after that. Only where
// the superblock (version 2 or 3, the only ones mbsflow writes) says a writer had the file
// open: a file cut short after a clean close is left as it is. The caller holds the
// file's WriterLock (or knows that nobody writes it).
bool grow_to_stored_end(const std::string& path);

}  // namespace mbsflow
