#include "io/output_set.h"

#include <fcntl.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/system/errors.h"

namespace seamvox {
namespace {

bool isFolder(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

/// A staged file moved onto its target: exchanged with an existing target (the temporary now
/// holds the old content) or renamed onto it (the target did not exist, or cannot be exchanged).
struct Move {
  AtomicFile* file;
  bool exchanged, created;
};

/// Puts the targets of moves back as they were, last first.
void undoMoves(const std::vector<Move>& moves) {
  for (auto it = moves.rbegin(); it != moves.rend(); ++it) {
    const char* target = it->file->path().c_str();
    if (it->exchanged) {
      ::renameat2(AT_FDCWD, it->file->temporaryPath().c_str(), AT_FDCWD, target, RENAME_EXCHANGE);
    } else if (it->created) {
      std::remove(target);
    }
  }
}

}  // namespace

AtomicFile& OutputSet::add(const std::string& target) {
  if (isFolder(target)) throw IoError(target + ": is a folder, not a file to write");
  for (const auto& file : files_) {
    if (isSameFile(file->path(), target)) {
      throw IoError(target + ": written twice by one run (also as " + file->path() + ")");
    }
  }
  files_.push_back(std::make_unique<AtomicFile>(target));
  return *files_.back();
}

void OutputSet::commit() {
  try {
    moveAllIntoPlace();
  } catch (...) {
    files_.clear();  // removes every temporary now, not when the set goes
    throw;
  }
  files_.clear();  // removes the temporaries, which now hold the replaced contents
}

void OutputSet::moveAllIntoPlace() {
  for (const auto& file : files_) file->close();
  std::vector<Move> moves;
  for (const auto& file : files_) {
    const std::string& target = file->path();
    const char* temporary = file->temporaryPath().c_str();
    struct stat st {};
    const bool exists = ::lstat(target.c_str(), &st) == 0;
    int err = 0;
    if (exists && S_ISDIR(st.st_mode)) {
      err = EISDIR;
    } else if (exists && ::renameat2(AT_FDCWD, temporary, AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
      moves.push_back({file.get(), true, false});
    } else if (std::rename(temporary, target.c_str()) == 0) {
      moves.push_back({file.get(), false, !exists});
    } else {
      err = errno;
    }
    if (err != 0) {
      undoMoves(moves);
      throw IoError(target + ": cannot move the finished output into place: " + std::strerror(err) +
                    (moves.empty() ? "" : " (the other outputs of this run were put back)"));
    }
  }
}

bool isSameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  const bool hasA = ::stat(a.c_str(), &sa) == 0, hasB = ::stat(b.c_str(), &sb) == 0;
  if (hasA && hasB) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (hasA != hasB) return false;
  std::error_code error;
  auto resolved = [&](const std::string& path) {
    std::error_code e;
    std::filesystem::path p = std::filesystem::absolute(path, e);
    if (!e) p = std::filesystem::weakly_canonical(p, e);
    if (e) error = e;
    return p;
  };
  const std::filesystem::path ca = resolved(a), cb = resolved(b);
  return error ? a == b : ca == cb;
}

}  // namespace seamvox
