#pragma once
/// Cleanup when a command is interrupted: on SIGINT, SIGTERM or SIGHUP the temporaries of
/// unfinished outputs (io/atomic_file.h registers them) are removed, registered child processes
/// (seamvox jobs) are stopped and waited for, and the process exits with 128 + the signal
/// (130, 143, 129). The handler only uses unlink, kill, waitpid, write and _exit.
#include <sys/types.h>

#include <atomic>
#include <cstdint>

namespace seamvox {

/// Installs the handler for SIGINT, SIGTERM and SIGHUP. A signal ignored at start (nohup, a
/// background job of a non-interactive shell) stays ignored.
void installInterruptCleanup();

/// Adds a file to remove on a signal; returns its slot, or -1 when the table (512 paths) is full
/// or the path is longer than PATH_MAX: that file is then left behind by a signal. A folder may
/// be registered too: it is removed after every registered file, if that leaves it empty (the
/// folders registered last first, so register a folder before the folders inside it).
int registerTemporary(const char* path);
void unregisterTemporary(int slot);

/// Adds a scratch folder whose files are named 0, 1, 2, ... (decimal, no extension): on a
/// signal, the files numbered below *fileCount (read then) are removed, then the folder. The
/// counter must outlive the registration. Returns the slot, or -1 when the table (64) is full.
int registerNumberedFolder(const char* path, const std::atomic<std::uint64_t>* fileCount);
void unregisterNumberedFolder(int slot);

/// Adds a child to stop (SIGTERM, then waited for) on a signal; returns its slot or -1.
int registerChild(pid_t pid);
void unregisterChild(int slot);

}  // namespace seamvox
