#include "commands.h"
#include "output_file.h"

int main(int argc, char** argv) {
    // Ctrl-C and SIGTERM remove the temporary files of unfinished outputs.
    hsnc::install_interrupt_cleanup();
    return hsnc::cli::run(argc, argv);
}
