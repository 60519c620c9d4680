// Reads an HdrHistogram interval log with HdrHistogram's own HistogramLogReader (Debian's
// libhdrhistogram-java): an independent decoder of what `mbstorm run --hlog` writes.
// Prints one line per interval:
//   interval <tag or -> <start s from StartTime> <total count> <max> <p50> <p99>
// (values: the lowest value of their bucket, so that they compare exactly; percentiles by
// nearest rank ceil(p * count / 100), in integers), one line per tag with the sums over all
// intervals:
//   total <tag or -> <count> <max> <p50> <p99>
// and writes the untagged intervals' sum as a percentile distribution (.hgrm) to args[1].
//   java -cp hdrhistogram.jar:<dir> HlogDump <log> <hgrm-out>
import java.io.PrintStream;
import java.util.Locale;
import java.util.Map;
import java.util.TreeMap;
import org.HdrHistogram.EncodableHistogram;
import org.HdrHistogram.Histogram;
import org.HdrHistogram.HistogramIterationValue;
import org.HdrHistogram.HistogramLogReader;

public class HlogDump {
    // Nearest rank, as mbstorm and HdrHistogram define it, in integer arithmetic.
    static long percentile(Histogram h, long numerator) {
        long total = h.getTotalCount();
        if (total == 0) return 0;
        long rank = Math.max(1, (total * numerator + 9999) / 10000);
        long cumulative = 0;
        for (HistogramIterationValue v : h.recordedValues()) {
            cumulative += v.getCountAtValueIteratedTo();
            if (cumulative >= rank) return h.lowestEquivalentValue(v.getValueIteratedTo());
        }
        return h.lowestEquivalentValue(h.getMaxValue());
    }

    static String describe(Histogram h) {
        long max = h.getTotalCount() == 0 ? 0 : h.lowestEquivalentValue(h.getMaxValue());
        return h.getTotalCount() + " " + max + " " + percentile(h, 5000) + " " + percentile(h, 9900);
    }

    public static void main(String[] args) throws Exception {
        HistogramLogReader reader = new HistogramLogReader(args[0]);
        Map<String, Histogram> totals = new TreeMap<>();
        EncodableHistogram encoded;
        while ((encoded = reader.nextIntervalHistogram()) != null) {
            Histogram h = (Histogram) encoded;
            String tag = h.getTag() == null ? "-" : h.getTag();
            double start = h.getStartTimeStamp() / 1000.0 - reader.getStartTimeSec();
            System.out.printf(Locale.US, "interval %s %.1f %s%n", tag, start, describe(h));
            Histogram sum = totals.get(tag);
            if (sum == null) totals.put(tag, h.copy());
            else sum.add(h);
        }
        for (Map.Entry<String, Histogram> e : totals.entrySet())
            System.out.println("total " + e.getKey() + " " + describe(e.getValue()));
        Histogram all = totals.get("-");
        if (all != null) {
            try (PrintStream out = new PrintStream(args[1])) {
                all.outputPercentileDistribution(out, 5, 1000000.0);
            }
        }
    }
}
