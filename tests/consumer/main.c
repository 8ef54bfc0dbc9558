#include <duet.h>
#include <stdio.h>

int main(void) {
  duet_device device = duet_device_new("threads=1");
  if (!device) return 1;
  printf("libduet %s (%d)\n", duet_get_version_string(), duet_get_version());
  duet_device_release(device);
  return 0;
}
