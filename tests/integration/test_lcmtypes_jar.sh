#!/usr/bin/env bash
# The Java jar of the message types (build/lcmtypes/rgbdslam_lcmtypes.jar), for lcm-spy: it
# holds one class per lcmtypes/*.lcm, and messages the C++ processes sent are decoded by it
# the way lcm-spy does it (the class whose LCM_FINGERPRINT matches the message's first 8
# bytes). The messages are recorded by lcm-logger from send-messages inside a private
# network namespace. Skips (exit 77) when there is no JDK or no lcm.jar (liblcm-java): the
# build then skips the jar too.
source "$(dirname "$0")/common.sh"
JAR=$BUILD/lcmtypes/rgbdslam_lcmtypes.jar
LCM_JAR=${LCM_JAR:-/usr/share/java/lcm.jar}
command -v java > /dev/null && command -v javac > /dev/null && command -v jar > /dev/null \
  || skip "no JDK (java, javac, jar): the message-type jar is not built"
[ -f "$LCM_JAR" ] || skip "no $LCM_JAR (install liblcm-java): the message-type jar is not built"
[ -f "$JAR" ] || fail "$JAR missing although Java and lcm.jar are here (build target rgbdslam_lcmtypes_jar)"

# 1. One class per .lcm file: rgbdslam_<name>_t.lcm -> rgbdslam/<name>_t.class.
jar tf "$JAR" > "$WORK/listing"
count=0
for lcm_file in "$SRC"/lcmtypes/*.lcm; do
  class=rgbdslam/$(basename "$lcm_file" .lcm | sed 's/^rgbdslam_//').class
  grep -qx "$class" "$WORK/listing" || fail "$class missing from the jar (from $(basename "$lcm_file"))"
  count=$((count + 1))
done
echo "jar: $count classes for $count .lcm files"

# 2. A log of real messages from the C++ side: 5 pose_t on SLAM_POSE, 1 status_t on
#    SLAM_STATUS (send-messages' "wrongtype" message is a valid status_t).
command -v lcm-logger > /dev/null || skip "lcm-logger (liblcm-bin) is missing"
require_netns
"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
timeout 30 lcm-logger --lcm-url='$LCM_URL' run.lcm > logger.out 2>&1 &
logger=\$!
sleep 0.5
'$TOOLS/send-messages' --poses 5 --lcm-url '$LCM_URL'
'$TOOLS/send-messages' --bad wrongtype --channel SLAM_STATUS --lcm-url '$LCM_URL'
sleep 0.5
kill -INT \$logger
wait \$logger || true
" || fail "recording the log failed: $(cat "$WORK/logger.out" 2>/dev/null)"

# 3. Decode it with the jar, as lcm-spy does.
mkdir -p "$WORK/check"
cat > "$WORK/check/JarCheck.java" <<'EOF'
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.EOFException;
import java.util.Enumeration;
import java.util.HashMap;
import java.util.Map;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;
import lcm.logging.Log;

// JarCheck JAR LOG: decodes every event of LOG with the class of JAR whose fingerprint
// matches; prints "CHANNEL CLASS" per event and "decoded N unknown U failed F".
public class JarCheck {
  public static void main(String[] args) throws Exception {
    Map<Long, Class<?>> byFingerprint = new HashMap<>();
    try (JarFile jar = new JarFile(args[0])) {
      for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
        String name = e.nextElement().getName();
        if (!name.endsWith(".class") || name.contains("$")) continue;
        Class<?> c = Class.forName(name.substring(0, name.length() - 6).replace('/', '.'));
        byFingerprint.put(c.getField("LCM_FINGERPRINT").getLong(null), c);
      }
    }
    Log log = new Log(args[1], "r");
    int decoded = 0, unknown = 0, failed = 0;
    for (int i = 0; i < 100000; i++) {
      Log.Event event;
      try {
        event = log.readNext();
      } catch (EOFException end) {
        break;
      }
      long fingerprint = new DataInputStream(new ByteArrayInputStream(event.data)).readLong();
      Class<?> c = byFingerprint.get(fingerprint);
      if (c == null) {
        unknown++;
        continue;
      }
      try {
        Object message = c.getConstructor(byte[].class).newInstance((Object) event.data);
        long utime = message.getClass().getField("utime").getLong(message);
        System.out.println(event.channel + " " + c.getName() + " utime " + utime);
        decoded++;
      } catch (Exception e) {
        System.out.println(event.channel + " " + c.getName() + " failed: " + e.getCause());
        failed++;
      }
    }
    System.out.println("decoded " + decoded + " unknown " + unknown + " failed " + failed);
  }
}
EOF
javac -nowarn -cp "$LCM_JAR" -d "$WORK/check" "$WORK/check/JarCheck.java" 2> "$WORK/javac.err" \
  || fail "javac failed: $(cat "$WORK/javac.err")"
java -cp "$LCM_JAR:$JAR:$WORK/check" JarCheck "$JAR" "$WORK/run.lcm" > "$WORK/decoded" 2>&1 \
  || fail "JarCheck failed: $(cat "$WORK/decoded")"
cat "$WORK/decoded"
grep -qx "decoded 6 unknown 0 failed 0" "$WORK/decoded" || fail "expected 6 decoded messages"
[ "$(grep -c '^SLAM_POSE rgbdslam.pose_t ' "$WORK/decoded")" -eq 5 ] || fail "pose_t not decoded on SLAM_POSE"
grep -q '^SLAM_STATUS rgbdslam.status_t ' "$WORK/decoded" || fail "status_t not decoded on SLAM_STATUS"
echo "PASS"
