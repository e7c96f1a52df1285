// Rethrowing an error with the context it was caught in.
#include "core/system/errors.h"

#include <exception>

namespace seamvox {

namespace {

template <class E>
[[noreturn]] void throwPrefixed(const std::string& context, const E& e) {
  const std::string message = e.what();
  if (message.compare(0, context.size(), context) == 0) throw e;
  throw E(context + ": " + message);
}

}  // namespace

void rethrowWithContext(const std::string& context) {
  try {
    throw;
  } catch (const IoError& e) {
    throwPrefixed(context, e);
  } catch (const InputError& e) {
    throwPrefixed(context, e);
  } catch (const TopologyError& e) {
    throwPrefixed(context, e);
  } catch (const SolverError& e) {
    throwPrefixed(context, e);
  } catch (const CancelledError&) {
    throw;  // "cancelled" needs no file
  }
}

}  // namespace seamvox
