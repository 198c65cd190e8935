;;;; tools/load-time.lisp -- make load-time: what loading the engine system costs (#W0RKSH).
;;;;
;;;; Usage (from the repository): make load-time
;;;; A fresh SBCL loads luv-physics into an empty ASDF cache (XDG_CACHE_HOME in a temporary
;;;; directory), which compiles the engine's two files, and then compiles the workshop on top;
;;;; three fresh SBCLs then load each from the compiled files.  Each child times its own
;;;; asdf:load-system, real and processor seconds, so SBCL's start is not counted.  Prints an Org
;;;; table, which make load-time splices into physics.org as the block engine-load-time.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(defun load-time-child (cache systems)
  "Run a fresh SBCL with the ASDF cache CACHE that loads each of SYSTEMS in turn; return, for
each, its real and processor seconds, as a list of two-element lists."
  (let* ((program (format nil "(progn (load ~S)
  (let ((times '()))
    (dolist (system '~S)
      (let ((real (get-internal-real-time)) (run (get-internal-run-time)))
        (let ((*standard-output* (make-broadcast-stream)) (*error-output* (make-broadcast-stream)))
          (asdf:load-system system))
        (push (list (/ (- (get-internal-real-time) real) (float internal-time-units-per-second 1d0))
                    (/ (- (get-internal-run-time) run) (float internal-time-units-per-second 1d0)))
              times)))
    (format t \"~~&load-time ~~S~~%\" (reverse times))))"
                          (namestring (merge-pathnames "tools/boot.lisp" *luv-root*)) systems))
         (output (uiop:run-program (list "env" (format nil "XDG_CACHE_HOME=~A" (namestring cache))
                                         "sbcl" "--dynamic-space-size" "4Gb" "--noinform" "--non-interactive"
                                         "--no-sysinit" "--no-userinit" "--eval" "(require :asdf)" "--eval" program)
                                   :directory *luv-root* :output :string :error-output :string
                                   :ignore-error-status t))
         (at (search "load-time " output)))
    (unless at
      (format *error-output* "load-time: the child printed no times:~%~A~%" output)
      (sb-ext:exit :code 1))
    (let ((*read-eval* nil)) (read-from-string output t nil :start (+ at 10)))))

(defun median (numbers)
  (let ((sorted (sort (copy-list numbers) #'<)))
    (nth (floor (length sorted) 2) sorted)))

(defun file-lines (name)
  (with-open-file (in (merge-pathnames name *luv-root*))
    (loop for line = (read-line in nil) while line count t)))

(defun load-average ()
  (with-open-file (in "/proc/loadavg") (read in)))

(let* ((cache (uiop:ensure-directory-pathname
               (format nil "/tmp/luv-load-time-~36R" (random (expt 36 8) (make-random-state t)))))
       (before (load-average)))
  (ensure-directories-exist cache)
  (unwind-protect
       (destructuring-bind (engine-compile workshop-compile)
           (load-time-child cache '("luv-physics" "luv-physics/workshop"))
         (let* ((loads (loop repeat 3 collect (load-time-child cache '("luv-physics" "luv-physics/workshop"))))
                (engine-load (list (median (mapcar #'first (mapcar #'first loads)))
                                   (median (mapcar #'second (mapcar #'first loads)))))
                (workshop-load (list (median (mapcar #'first (mapcar #'second loads)))
                                     (median (mapcar #'second (mapcar #'second loads))))))
           (format t "| system                | files                                              | lines | step                           | real s | processor s |~%")
           (format t "|-----------------------+----------------------------------------------------+-------+--------------------------------+--------+-------------|~%")
           (loop for (system files step (real run)) in
                 `(("luv-physics" ("tangled/physics.lisp" "tangled/physics-simd.lisp") "compile from an empty cache" ,engine-compile)
                   ("luv-physics" () "load compiled (median of 3)" ,engine-load)
                   ("luv-physics/workshop" ("tangled/workshop.lisp") "compile, the engine loaded" ,workshop-compile)
                   ("luv-physics/workshop" () "load compiled (median of 3)" ,workshop-load))
                 do (format t "| ~21A | ~50A | ~5@A | ~30A | ~6,2F | ~11,2F |~%"
                            system (format nil "~{~A~^, ~}" files)
                            (if files (reduce #'+ (mapcar #'file-lines files)) "")
                            step real run))
           (format t "~%SBCL ~A, load average ~,2F before and ~,2F after the runs, on ~D cores~%"
                   (lisp-implementation-version) before (load-average)
                   (with-open-file (in "/proc/cpuinfo")
                     (loop for line = (read-line in nil) while line
                           count (eql 0 (search "processor" line)))))))
    (uiop:delete-directory-tree cache :validate t :if-does-not-exist :ignore)))
