#!/bin/sh
# SPDX-License-Identifier: MIT
# /init of the USB test guest (tests/kernel/initramfs.py): mounts the kernel
# file systems, loads the USB modules in dependency order, runs the
# scenario that run_guest.py appended (/scenario.sh), prints its exit code
# as "FDSURF-EXIT <n>" and powers off.
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
for module in $(cat /modules.order); do
  insmod "/lib/modules/$module" || echo "FDSURF-ERROR insmod $module failed"
done
mount -t configfs configfs /sys/kernel/config
echo "FDSURF-USERSPACE $(cut -d' ' -f1 /proc/uptime)"
if [ -f /scenario.sh ]; then
  sh /scenario.sh
  echo "FDSURF-EXIT $?"
else
  echo "FDSURF-ERROR no /scenario.sh"
fi
poweroff -f
