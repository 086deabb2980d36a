/* The C API from a C99 program: version, status strings, last-error, struct_size checks,
 * create/destroy, destroy(NULL). Prints "capi_c_test: N checks passed" or FAILED lines. */
#include <emf/emf.h>
#include <stdio.h>
#include <string.h>

static int g_checks = 0;
static int g_failed = 0;

#define CHECK(cond)                                                         \
  do {                                                                      \
    ++g_checks;                                                             \
    if (!(cond)) {                                                          \
      ++g_failed;                                                           \
      printf("FAILED %s:%d: %s (last error: %s)\n", __FILE__, __LINE__, #cond, \
             emf_last_error_message());                                     \
    }                                                                       \
  } while (0)

int main(void) {
  emf_system_options opts;
  emf_system* sys = NULL;
  emf_system_info info;
  emf_status s;

  CHECK(emf_version() == EMF_VERSION);
  CHECK(strcmp(emf_version_string(), "0.1.0") == 0 || EMF_VERSION != 100);
  CHECK(strcmp(emf_status_string(EMF_OK), "EMF_OK") == 0);
  CHECK(strcmp(emf_status_string(EMF_ERROR_CONFIG), "EMF_ERROR_CONFIG") == 0);
  CHECK(strcmp(emf_status_string((emf_status)12345), "EMF_STATUS_UNKNOWN") == 0);

  emf_system_destroy(NULL); /* no-op */

  /* NULL options */
  s = emf_system_create(NULL, &sys);
  CHECK(s == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(sys == NULL);
  CHECK(strstr(emf_last_error_message(), "emf_system_options is NULL") != NULL);

  /* struct_size too small */
  emf_system_options_init(&opts);
  opts.struct_size = 4;
  s = emf_system_create(&opts, &sys);
  CHECK(s == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(emf_last_error_message(), "struct_size") != NULL);

  /* newer major version than the library */
  emf_system_options_init(&opts);
  opts.api_version = (EMF_VERSION_MAJOR + 1) * 10000;
  s = emf_system_create(&opts, &sys);
  CHECK(s == EMF_ERROR_VERSION_MISMATCH);

  /* bad configuration: unknown key, named in the message */
  emf_system_options_init(&opts);
  opts.config_yaml = "map:\n  memroy_mb: 12\n";
  s = emf_system_create(&opts, &sys);
  CHECK(s == EMF_ERROR_CONFIG);
  CHECK(strstr(emf_last_error_message(), "map.memroy_mb") != NULL);
  CHECK(strstr(emf_last_error_message(), "map.memory_mb") != NULL);

  /* missing config file */
  emf_system_options_init(&opts);
  opts.config_file = "/nonexistent/emf.yaml";
  s = emf_system_create(&opts, &sys);
  CHECK(s == EMF_ERROR_CONFIG);
  CHECK(strstr(emf_last_error_message(), "/nonexistent/emf.yaml") != NULL);

  /* success */
  emf_system_options_init(&opts);
  opts.config_yaml = "map:\n  memory_mb: 16\n";
  s = emf_system_create(&opts, &sys);
  CHECK(s == EMF_OK);
  CHECK(sys != NULL);
  CHECK(emf_last_error_message()[0] == '\0');
  memset(&info, 0, sizeof(info));
  info.struct_size = sizeof(info);
  s = emf_system_get_info(sys, &info);
  CHECK(s == EMF_OK);
  CHECK(strlen(info.device_name) > 0);
  printf("device: %s (%s)\n", info.device_name, info.platform_name);
  info.struct_size = 1;
  CHECK(emf_system_get_info(sys, &info) == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(emf_system_get_info(NULL, &info) == EMF_ERROR_INVALID_ARGUMENT);
  emf_system_destroy(sys);

  if (g_failed == 0) printf("capi_c_test: %d checks passed\n", g_checks);
  return g_failed == 0 ? 0 : 1;
}
