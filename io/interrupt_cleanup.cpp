#include "io/interrupt_cleanup.h"

#include <limits.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <initializer_list>

namespace seamvox {
namespace {

// A slot is free, being filled, or live; the handler reads live slots only. Fixed tables (no
// allocation) because the handler may run in the middle of malloc.
enum SlotState : int { kFree = 0, kFilling = 1, kLive = 2 };
constexpr int kPathSlots = 512, kChildSlots = 256, kFolderSlots = 64;

struct PathSlot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
struct ChildSlot {
  std::atomic<int> state{kFree};
  pid_t pid = 0;
};
struct FolderSlot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
  const std::atomic<std::uint64_t>* fileCount = nullptr;
};
PathSlot pathSlots[kPathSlots];
ChildSlot childSlots[kChildSlots];
FolderSlot folderSlots[kFolderSlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free flags");

template <class Slot, int N>
int claimSlot(Slot (&slots)[N]) {
  for (int i = 0; i < N; ++i) {
    int expected = kFree;
    if (slots[i].state.compare_exchange_strong(expected, kFilling)) return i;
  }
  return -1;
}

void writeMessage(const char* text) {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

// Removes the numbered files of a scratch folder, then the folder (async-signal-safe: the
// names are formatted by hand).
void removeNumberedFolder(const FolderSlot& slot) {
  char path[PATH_MAX + 24];
  std::size_t base = std::strlen(slot.path);
  std::memcpy(path, slot.path, base);
  path[base++] = '/';
  const std::uint64_t count = slot.fileCount->load();
  for (std::uint64_t i = 0; i < count; ++i) {
    char digits[24];
    int n = 0;
    std::uint64_t x = i;
    do {
      digits[n++] = static_cast<char>('0' + x % 10);
      x /= 10;
    } while (x);
    for (int k = 0; k < n; ++k) path[base + k] = digits[n - 1 - k];
    path[base + n] = '\0';
    ::unlink(path);
  }
  ::rmdir(slot.path);
}

void onInterrupt(int signal) {
  const int savedErrno = errno;
  for (ChildSlot& slot : childSlots) {
    if (slot.state.load() == kLive) ::kill(slot.pid, SIGTERM);
  }
  for (PathSlot& slot : pathSlots) {
    if (slot.state.load() == kLive) ::unlink(slot.path);
  }
  for (FolderSlot& slot : folderSlots) {
    if (slot.state.load() == kLive) removeNumberedFolder(slot);
  }
  // Folders, now that their registered files are gone; the last registered (inner) first.
  for (int i = kPathSlots - 1; i >= 0; --i) {
    if (pathSlots[i].state.load() == kLive) ::rmdir(pathSlots[i].path);
  }
  // The children remove their own temporaries before they exit.
  for (ChildSlot& slot : childSlots) {
    if (slot.state.load() == kLive) {
      while (::waitpid(slot.pid, nullptr, 0) < 0 && errno == EINTR) {
      }
    }
  }
  writeMessage(signal == SIGINT    ? "\nseamvox: interrupted; unfinished outputs removed\n"
               : signal == SIGHUP ? "\nseamvox: hangup; unfinished outputs removed\n"
                                  : "\nseamvox: terminated; unfinished outputs removed\n");
  errno = savedErrno;
  ::_exit(128 + signal);
}

}  // namespace

void installInterruptCleanup() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  for (const int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&action.sa_mask, s);
  for (const int s : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction previous {};
    if (sigaction(s, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
    sigaction(s, &action, nullptr);
  }
}

int registerTemporary(const char* path) {
  if (std::strlen(path) >= PATH_MAX) return -1;
  const int slot = claimSlot(pathSlots);
  if (slot < 0) return -1;
  std::strcpy(pathSlots[slot].path, path);
  pathSlots[slot].state.store(kLive);
  return slot;
}

void unregisterTemporary(int slot) {
  if (slot >= 0 && slot < kPathSlots) pathSlots[slot].state.store(kFree);
}

int registerNumberedFolder(const char* path, const std::atomic<std::uint64_t>* fileCount) {
  if (std::strlen(path) >= PATH_MAX) return -1;
  const int slot = claimSlot(folderSlots);
  if (slot < 0) return -1;
  std::strcpy(folderSlots[slot].path, path);
  folderSlots[slot].fileCount = fileCount;
  folderSlots[slot].state.store(kLive);
  return slot;
}

void unregisterNumberedFolder(int slot) {
  if (slot >= 0 && slot < kFolderSlots) folderSlots[slot].state.store(kFree);
}

int registerChild(pid_t pid) {
  const int slot = claimSlot(childSlots);
  if (slot < 0) return -1;
  childSlots[slot].pid = pid;
  childSlots[slot].state.store(kLive);
  return slot;
}

void unregisterChild(int slot) {
  if (slot >= 0 && slot < kChildSlots) childSlots[slot].state.store(kFree);
}

}  // namespace seamvox
