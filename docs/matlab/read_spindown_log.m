function r = read_spindown_log(logfile, bench)
%READ_SPINDOWN_LOG  One bench's samples from a spindown LCM log, and a viscous fit of its first run.
%   r = read_spindown_log('lab.lcm', 'bench000') reads the log with LCM's own Java log reader and
%   spindown's message classes, as LCM's MATLAB tutorial does, and fits the viscous model
%   J dw/dt = -c1 w to the first spin-down. r has the samples (t in s of device time, v in the
%   reading's unit), the bench's J and K_b from its CONFIG message, the fitted c1 (N*m*s/rad)
%   and omega0 (rad/s), and c1 as spindown-fitter found it (its FIT message), for comparison.
%
%   Before the first call, put both jars on MATLAB's Java class path (once per session):
%     javaaddpath('/usr/share/java/lcm.jar');              % Debian's liblcm-java, or your LCM build
%     javaaddpath('build/lcmtypes/spindown_types.jar');    % cmake --build build --target spindown_types_jar
%   MATLAB's bundled Java is 8, which loads class files of major version 52 or lower. spindown's
%   build compiles the types jar with javac --release 8 (52), and Debian's lcm.jar is 52 too; a
%   jar built for a newer Java fails here with "UnsupportedClassVersionError".
%   (docs/using-the-data.md; the same calls are checked by ctest -R java_matlab_route.)

if nargin < 2
    error('usage: r = read_spindown_log(LOGFILE, BENCH)');
end
sample_channel = ['SPINDOWN.' bench '.SAMPLE'];
config_channel = ['SPINDOWN.' bench '.CONFIG'];
fit_channel = ['SPINDOWN.' bench '.FIT'];

r = struct('bench', bench, 't', [], 'v', [], 'unit', '', 'J', NaN, 'Kb', NaN, ...
           't_cut', NaN, 't_stop', NaN, 'c1', NaN, 'omega0', NaN, 'c1_fitter', NaN);
tc = {};   % one cell per SAMPLE message: growing one array event by event is slow
vc = {};
units = {'V', 'rpm', 'rad/s'};   % samples_t.QUANTITY_BACK_EMF_V, _RPM, _RAD_S

lcmlog = lcm.logging.Log(logfile, 'r');   % not "log": that is MATLAB's log()
while true
    try
        ev = lcmlog.readNext();
    catch
        break;   % java.io.EOFException: the end of the log
    end
    channel = char(ev.channel);
    if strcmp(channel, sample_channel)
        m = spindown.samples_t(ev.data);
        tc{end + 1} = double(m.device_time_us(:)) * 1e-6;
        vc{end + 1} = double(m.value(:));
        r.unit = units{double(m.quantity) + 1};
    elseif strcmp(channel, config_channel)
        c = spindown.config_t(ev.data);
        r.J = c.inertia_kg_m2;
        r.Kb = c.kb_v_s_per_rad;
    elseif strcmp(channel, fit_channel) && isnan(r.t_cut)
        f = spindown.fit_t(ev.data);   % the first run's fit, as spindown-fitter published it
        r.t_cut = f.t_cut_s;
        r.t_stop = f.t_stop_s;
        names = cell(f.param_name);
        models = cell(f.model);
        for k = 1:double(f.nparams)
            if strcmp(names{k}, 'c1') && strcmp(models{double(f.param_model(k)) + 1}, 'viscous')
                r.c1_fitter = f.param_value(k);
            end
        end
    end
end
lcmlog.close();

r.t = vertcat(tc{:});
r.v = vertcat(vc{:});
if isempty(r.t)
    error('no samples of bench %s in %s', bench, logfile);
end
fprintf('%s: bench %s, %d samples (%s), J = %g kg*m^2, K_b = %g V*s/rad\n', logfile, bench, ...
        numel(r.t), r.unit, r.J, r.Kb);

% The coast of the first run: from the cut (the fitter's, or the highest reading without a FIT)
% to the stop, and only while the reading is above 5 % of its value at the cut: the viscous
% model never reaches zero, so the stop itself is left out.
if isnan(r.t_cut)
    [~, i] = max(r.v);
    r.t_cut = r.t(i);
end
after = find(r.t >= r.t_cut);
v_cut = r.v(after(1));
last = find(r.v(after) < 0.05 * v_cut, 1) - 1;
if isempty(last)
    last = numel(after);
end
k = after(1:last);
if ~isnan(r.t_stop)
    k = k(r.t(k) <= r.t_stop);
end
tt = r.t(k) - r.t_cut;
vv = r.v(k);

% v = v0 * exp(-(c1/J) * t): a straight line through log(v) to start, then least squares on v.
p = polyfit(tt, log(vv), 1);
sse = @(q) sum((vv - q(1) * exp(-q(2) * tt)).^2);
q = fminsearch(sse, [exp(p(2)), -p(2)]);
rate = q(2);   % 1/s: c1/J
r.c1 = rate * r.J;
switch r.unit
    case 'V'
        r.omega0 = q(1) / r.Kb;
    case 'rpm'
        r.omega0 = q(1) * pi / 30;
    otherwise
        r.omega0 = q(1);
end
fprintf('viscous fit of %d samples from t = %.3f s: c1 = %.4g N*m*s/rad, omega0 = %.4g rad/s\n', ...
        numel(k), r.t_cut, r.c1, r.omega0);
if ~isnan(r.c1_fitter)
    fprintf('spindown-fitter''s viscous c1 (stop modelled, whole coast): %.4g N*m*s/rad\n', r.c1_fitter);
end

plot(r.t, r.v, '.', tt + r.t_cut, q(1) * exp(-q(2) * tt), '-');
xlabel('device time (s)');
ylabel(['reading (' r.unit ')']);
legend('samples', 'viscous fit');
title(['spindown bench ' bench]);
end
