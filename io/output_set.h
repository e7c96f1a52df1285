#pragma once
/// All-or-nothing output of one command run: several files staged as temporaries
/// (io/atomic_file.h) and moved into place together, only once every one of them was written.
#include <memory>
#include <string>
#include <vector>

#include "io/atomic_file.h"

namespace seamvox {

/// Stage each output with add(), write it, then commit() once. If a write or a move fails, no
/// target is created or replaced and every temporary is removed; so it is when the set is
/// destroyed uncommitted (an exception) or the process is interrupted.
class OutputSet {
 public:
  OutputSet() = default;
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Opens the temporary of target now, so a missing or read-only folder fails before the work.
  /// Throws IoError naming target when it cannot be created, is a folder or is staged already.
  AtomicFile& add(const std::string& target);
  /// Closes every temporary, then moves each onto its target. When a move fails, the targets
  /// moved before are put back (replaced ones exchanged back with renameat2 RENAME_EXCHANGE,
  /// created ones removed) and IoError names the target that failed. On a filesystem without
  /// RENAME_EXCHANGE a replaced target cannot be put back and keeps its new content. Either way
  /// the set is empty afterwards and no temporary is left.
  void commit();
  std::size_t size() const { return files_.size(); }

 private:
  void moveAllIntoPlace();
  std::vector<std::unique_ptr<AtomicFile>> files_;
};

/// Whether two paths name the same file: the same device and inode when both exist, otherwise
/// the same absolute path once symbolic links, "." and ".." are resolved.
bool isSameFile(const std::string& a, const std::string& b);

}  // namespace seamvox
