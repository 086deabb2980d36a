/* An out-of-tree program using an installed emf. */
#include <emf/emf.h>
#include <stdio.h>

int main(void) {
  emf_system_options opts;
  emf_system* sys = NULL;
  emf_system_options_init(&opts);
  if (emf_system_create(&opts, &sys) != EMF_OK) {
    printf("create failed: %s\n", emf_last_error_message());
    return 1;
  }
  emf_system_destroy(sys);
  printf("emf %s\n", emf_version_string());
  return 0;
}
