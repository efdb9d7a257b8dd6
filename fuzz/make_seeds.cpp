// Writes the seed corpus of every fuzz target: make_seeds OUT_DIR SOURCE_DIR.
#include <cstdio>
#include <exception>

#include "fuzz_seeds.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_seeds OUT_DIR SOURCE_DIR\n");
    return 2;
  }
  try {
    ringtrack::fuzz::write_all_seeds(argv[1], argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
