#include <iostream>

#include "cli.hpp"

int main(int argc, char** argv) { return ccmap::tools::run_cli(argc, argv, std::cout, std::cerr); }
