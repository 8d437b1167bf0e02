// What MATLAB does with a spindown log, in Java 8 (compiled with javac --release 8, as MATLAB's
// bundled Java 8 needs): open the log with lcm.logging.Log, decode every SPINDOWN.* channel with
// the classes of spindown_types.jar, and check the samples against `spindown export --csv` of the
// same log. Also checks that every class of the types jar is class file major version 52 (Java 8)
// and that lcm.jar's are no newer, or MATLAB could not load them.
//
//   java -cp lcm.jar:spindown_types.jar:. SpindownLogCheck TYPES_JAR LCM_JAR LOG SAMPLES_CSV
//
// Prints what it decoded; exits 1 with "FAIL: ..." on the first thing that is wrong.
import java.io.BufferedReader;
import java.io.DataInputStream;
import java.io.EOFException;
import java.io.File;
import java.io.FileInputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.InputStreamReader;
import java.nio.charset.StandardCharsets;
import java.util.ArrayList;
import java.util.Enumeration;
import java.util.List;
import java.util.Map;
import java.util.TreeMap;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;

public class SpindownLogCheck {
    static final int JAVA8_MAJOR = 52;
    static final long MAX_EVENTS = 10000000L;  // a bound on the loop, far above any test log

    static void fail(String why) {
        System.out.println("FAIL: " + why);
        System.exit(1);
    }

    // Major version of every class file in a jar: {lowest, highest, count}.
    static int[] classMajors(String jarPath) throws IOException {
        int lo = Integer.MAX_VALUE, hi = 0, n = 0;
        JarFile jar = new JarFile(jarPath);
        try {
            for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
                JarEntry entry = e.nextElement();
                if (!entry.getName().endsWith(".class")) continue;
                InputStream in = jar.getInputStream(entry);
                try {
                    DataInputStream d = new DataInputStream(in);
                    if (d.readInt() != 0xCAFEBABE) fail(jarPath + ": " + entry.getName() + " is not a class file");
                    d.readUnsignedShort();  // minor
                    int major = d.readUnsignedShort();
                    lo = Math.min(lo, major);
                    hi = Math.max(hi, major);
                    ++n;
                } finally {
                    in.close();
                }
            }
        } finally {
            jar.close();
        }
        return new int[] {lo, hi, n};
    }

    // One sample as spindown export writes it (bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch).
    static final class Sample {
        String bench;
        long seq;
        long deviceUs;
        long hostUs;
        double value;
        int rawAdc;
        int clockEpoch;
    }

    static double parseNumber(String s) {
        if (s.equals("NaN")) return Double.NaN;
        if (s.equals("Inf")) return Double.POSITIVE_INFINITY;
        if (s.equals("-Inf")) return Double.NEGATIVE_INFINITY;
        return Double.parseDouble(s);
    }

    static boolean sameValue(double a, double b) {
        if (Double.isNaN(a) || Double.isNaN(b)) return Double.isNaN(a) && Double.isNaN(b);
        if (Double.isInfinite(a) || Double.isInfinite(b)) return a == b;
        return Math.abs(a - b) <= 1e-9 * Math.max(1.0, Math.abs(b));  // export prints 10 significant digits
    }

    public static void main(String[] args) throws Exception {
        if (args.length != 4) {
            System.err.println("usage: SpindownLogCheck TYPES_JAR LCM_JAR LOG SAMPLES_CSV");
            System.exit(2);
        }
        String typesJar = args[0], lcmJar = args[1], logPath = args[2], csvPath = args[3];

        int[] t = classMajors(typesJar);
        if (t[2] < 6) fail(typesJar + " holds only " + t[2] + " classes");
        if (t[0] != JAVA8_MAJOR || t[1] != JAVA8_MAJOR)
            fail(typesJar + ": class file major versions " + t[0] + ".." + t[1] + ", want " + JAVA8_MAJOR
                 + " (Java 8) for MATLAB: build it with javac --release 8");
        int[] l = classMajors(lcmJar);
        if (l[1] > JAVA8_MAJOR) fail(lcmJar + ": class file major version up to " + l[1] + ", MATLAB's Java 8 loads " + JAVA8_MAJOR);
        System.out.println("class files: " + t[2] + " in " + new File(typesJar).getName() + " all major " + JAVA8_MAJOR
                           + "; " + l[2] + " in " + new File(lcmJar).getName() + " major " + l[0] + ".." + l[1]);

        // The log, as MATLAB reads it: readNext until the end of the file (an EOFException).
        lcm.logging.Log log = new lcm.logging.Log(logPath, "r");
        Map<String, Integer> perChannel = new TreeMap<String, Integer>();
        Map<String, Integer> perType = new TreeMap<String, Integer>();
        List<Sample> samples = new ArrayList<Sample>();
        long events = 0;
        try {
            while (true) {
                if (++events > MAX_EVENTS) fail("more than " + MAX_EVENTS + " events");
                lcm.logging.Log.Event ev = log.readNext();
                if (!ev.channel.startsWith("SPINDOWN.")) continue;
                String[] part = ev.channel.split("\\.");
                if (part.length != 3) fail("channel " + ev.channel + " is not SPINDOWN.<bench>.<KIND>");
                String bench = part[1], kind = part[2], type, named;
                try {
                    if (kind.equals("SAMPLE")) {
                        spindown.samples_t m = new spindown.samples_t(ev.data);
                        type = "samples_t";
                        named = m.bench;
                        if (m.device_time_us.length != m.n || m.value.length != m.n) fail(ev.channel + ": arrays not of length n");
                        for (int i = 0; i < m.n; ++i) {
                            Sample s = new Sample();
                            s.bench = bench;
                            s.seq = m.seq + i;
                            s.deviceUs = m.device_time_us[i];
                            s.hostUs = m.host_time_us[i];
                            s.value = m.value[i];
                            s.rawAdc = m.raw_adc[i];
                            s.clockEpoch = m.clock_epoch;
                            samples.add(s);
                        }
                    } else if (kind.equals("CONFIG")) {
                        spindown.config_t m = new spindown.config_t(ev.data);
                        type = "config_t";
                        named = m.bench;
                        if (!(m.inertia_kg_m2 > 0) || !(m.kb_v_s_per_rad > 0)) fail(ev.channel + ": J or K_b not positive");
                    } else if (kind.equals("RUN")) {
                        spindown.run_t m = new spindown.run_t(ev.data);
                        type = "run_t";
                        named = m.bench;
                    } else if (kind.equals("FIT")) {
                        spindown.fit_t m = new spindown.fit_t(ev.data);
                        type = "fit_t";
                        named = m.bench;
                        if (m.nmodels != m.model.length || m.nparams != m.param_name.length) fail(ev.channel + ": FIT arrays");
                        boolean viscous = false;
                        for (int k = 0; k < m.nparams; ++k)
                            if (m.param_name[k].equals("c1") && m.model[m.param_model[k]].equals("viscous")) viscous = true;
                        if (!viscous) fail(ev.channel + ": FIT run " + m.run + " has no viscous c1");
                    } else if (kind.equals("EXPLAIN")) {
                        spindown.explain_t m = new spindown.explain_t(ev.data);
                        type = "explain_t";
                        named = m.bench;
                    } else if (kind.equals("STATUS")) {
                        spindown.status_t m = new spindown.status_t(ev.data);
                        type = "status_t";
                        // SPINDOWN.<bench>.STATUS from a bridge, SPINDOWN.<service>.STATUS from the others
                        named = m.service.equals(bench) ? bench : m.instance;
                    } else {
                        fail("channel " + ev.channel + ": no spindown type for " + kind);
                        return;
                    }
                } catch (IOException e) {
                    fail("event " + ev.eventNumber + " on " + ev.channel + " does not decode: " + e.getMessage());
                    return;
                }
                if (!named.equals(bench)) fail(ev.channel + ": message names '" + named + "'");
                Integer c = perChannel.get(ev.channel);
                perChannel.put(ev.channel, c == null ? 1 : c + 1);
                c = perType.get(type);
                perType.put(type, c == null ? 1 : c + 1);
            }
        } catch (EOFException end) {
            // the end of the log
        } finally {
            log.close();
        }
        for (Map.Entry<String, Integer> e : perChannel.entrySet())
            System.out.println("decoded " + e.getValue() + " on " + e.getKey());
        for (String type : new String[] {"samples_t", "config_t", "run_t", "fit_t", "explain_t", "status_t"})
            if (!perType.containsKey(type)) fail("no " + type + " message in the log");

        // The same samples as spindown export --csv, row for row.
        BufferedReader csv = new BufferedReader(new InputStreamReader(new FileInputStream(csvPath), StandardCharsets.UTF_8));
        int rows = 0;
        try {
            String header = csv.readLine();
            if (header == null || !header.startsWith("bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch"))
                fail(csvPath + ": unexpected header " + header);
            for (String line; (line = csv.readLine()) != null;) {
                if (rows >= samples.size()) fail("the CSV has more rows than the " + samples.size() + " samples in the log");
                String[] f = line.split(",", -1);
                Sample s = samples.get(rows);
                String where = "sample " + (rows + 1) + " (" + line + ")";
                if (!f[0].equals(s.bench)) fail(where + ": bench " + s.bench + " in the log");
                if (Long.parseLong(f[1]) != s.seq) fail(where + ": seq " + s.seq + " in the log");
                if (Math.round(Double.parseDouble(f[2]) * 1e6) != s.deviceUs) fail(where + ": device time " + s.deviceUs + " us in the log");
                if (Math.round(Double.parseDouble(f[3]) * 1e6) != s.hostUs) fail(where + ": host time " + s.hostUs + " us in the log");
                if (!sameValue(s.value, parseNumber(f[4]))) fail(where + ": value " + s.value + " in the log");
                if ((f[6].isEmpty() ? -1 : Integer.parseInt(f[6])) != s.rawAdc) fail(where + ": raw_adc " + s.rawAdc + " in the log");
                if (Integer.parseInt(f[7]) != s.clockEpoch) fail(where + ": clock_epoch " + s.clockEpoch + " in the log");
                ++rows;
            }
        } finally {
            csv.close();
        }
        if (rows != samples.size()) fail("the CSV has " + rows + " rows, the log " + samples.size() + " samples");
        if (rows == 0) fail("no samples");
        System.out.println("PASS: " + (events - 1) + " events, " + perChannel.size() + " spindown channels decoded; " + rows
                           + " samples equal to spindown export's");
    }
}
