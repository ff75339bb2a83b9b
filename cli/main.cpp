#include "commands.h"

int main(int argc, char** argv) { return hsnc::cli::run(argc, argv); }
