// Table-driven checks of a reader's refusals: each malformed input must be
// refused with the given exception type, by a message naming where (the
// file, and line when there is one) and what was wrong.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace plsa::test {

struct Refusal {
  std::string input;  // what the reader is given
  std::string says;   // a part of the message it must refuse it with
};

template <class Error, class Read>
void expectEachRefused(const std::vector<Refusal>& cases, Read read, const std::string& where) {
  for (const Refusal& c : cases) {
    try {
      read(c.input);
      ADD_FAILURE() << "accepted: " << c.input;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(where), std::string::npos) << what << "\nwanted it to name: " << where;
      EXPECT_NE(what.find(c.says), std::string::npos) << what << "\nwanted: " << c.says;
    }
  }
}

}  // namespace plsa::test
