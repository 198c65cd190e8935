;;;; tests/run.lisp -- run the claims of physics.org; the last line says "claims: N passed, N failed".
;;;;
;;;; Usage: sbcl --non-interactive --no-sysinit --no-userinit --load tests/run.lisp
;;;; With ANCHOR=XXXXXX in the environment, only the claims of that section run.
;;;; A claim passes when it made at least one check and every check passed.
;;;; Prints one line per part of the page (a top-level heading) with its claims' counts and
;;;; seconds, and each failing claim's name with what failed; what the claims themselves print
;;;; (FiveAM's dots and report, the notes of the kernels some of them compile) goes to
;;;; report/claims.log, and each claim's seconds to report/claim-times.tsv.
;;;; Exit status: 0 if every selected claim passed, 1 otherwise (or if none ran),
;;;; 2 if the systems did not load.

(load (merge-pathnames "../tools/boot.lisp" *load-truename*))

(in-package #:cl-user)

(defun finish-claims (passed failed code)
  "Print the closing summary line and exit with CODE."
  (format t "~&claims: ~D passed, ~D failed~%" passed failed)
  (finish-output)
  (sb-ext:exit :code code))

(when (luv-load-systems "luv-physics/tests")
  (finish-claims 0 1 2))

(defparameter *claims-log* (merge-pathnames "report/claims.log" *luv-root*)
  "Where what the claims print goes.")

(defparameter *claim-times* (merge-pathnames "report/claim-times.tsv" *luv-root*)
  "Each claim run: seconds, anchor, name, passed or FAILED, tab-separated, in the order run.")

(defun claim-passed-p (name results)
  "True if the FiveAM RESULTS of test NAME are not empty and all passed."
  (let ((own (remove name results :key (lambda (r) (5am::name (5am::test-case r))) :test-not #'eq)))
    (and own (every #'5am::test-passed-p own))))

(defun page-parts ()
  "A hash table from each anchor of physics.org to the title of the top-level heading it is under."
  (let ((parts (make-hash-table :test 'equal)) (title nil))
    (with-open-file (in (merge-pathnames "physics.org" *luv-root*) :external-format :utf-8)
      (loop for line = (read-line in nil) while line
            do (cond ((and (> (length line) 1) (string= "* " line :end2 2))
                      (setf title (string-trim " " (subseq line 2 (or (search " :" line :from-end t)
                                                                      (length line))))))
                     ((and title (search ":CUSTOM_ID:" line))
                      (setf (gethash (string-trim " " (subseq line (+ 11 (search ":CUSTOM_ID:" line))))
                                     parts)
                            title)))))
    parts))

(defun claims-in-run-order (suite)
  "The claims of SUITE, a suite of anchors or of one anchor, as (ANCHOR . NAME) in the order
FiveAM runs them."
  (let ((test (5am:get-test suite)))
    (if (typep test '5am::test-suite)
        (loop for child being the hash-values of (5am::tests test)
              append (claims-in-run-order (if (symbolp child) child (5am::name child))))
        (let ((claim (rassoc suite luv-physics-tests:*claims*)))
          (and claim (list claim))))))

(defun squeeze-blanks (text)
  "TEXT on one line: each run of spaces, tabs and newlines one space, none at either end."
  (let ((out (make-string-output-stream)) (blank nil))
    (loop for c across (string-trim '(#\Space #\Tab #\Newline) text)
          do (if (member c '(#\Space #\Tab #\Newline))
                 (setf blank t)
                 (progn (when blank (write-char #\Space out) (setf blank nil))
                        (write-char c out))))
    (get-output-stream-string out)))

(defun failure-lines (name results)
  "What failed in the FiveAM RESULTS of claim NAME, one string per failed check or error."
  (let ((own (remove name results :key (lambda (r) (5am::name (5am::test-case r))) :test-not #'eq)))
    (or (loop for r in own
              unless (5am::test-passed-p r)
                collect (squeeze-blanks (princ-to-string (or (5am::reason r) (type-of r)))))
        (list "the claim made no check"))))

(let* ((anchor (string-upcase (string-trim " #" (or (sb-ext:posix-getenv "ANCHOR") ""))))
       (all (string= anchor ""))
       (suite (if all 'luv-physics-tests:claims (find-symbol anchor '#:luv-physics-tests)))
       (selected (and suite (claims-in-run-order suite)))
       (parts (page-parts))
       (times '())
       (passed 0) (failed 0) (failures '()))
  ;; a section of the page whose claims all live in its neighbours runs none and passes; an
  ;; anchor the page has not got is a mistake
  (when (and (null selected) (not all) (gethash anchor parts))
    (format t "~&Section ~A (under ~A) has no claims of its own.~%" anchor (gethash anchor parts))
    (finish-claims 0 0 0))
  (when (null selected)
    (if all
        (format t "~&No claims are defined.~%")
        (format t "~&No claims for anchor ~A. Anchors with claims: ~{~A~^ ~}~%"
                anchor (remove-duplicates (mapcar #'car luv-physics-tests:*claims*)
                                          :test #'string= :from-end t)))
    (finish-claims 0 0 1))
  (format t "~&claims: ~D to run; what they print is in ~A~%"
          (length selected) (enough-namestring *claims-log* *luv-root*))
  (finish-output)
  (with-open-file (log *claims-log* :direction :output :if-exists :supersede :external-format :utf-8)
    (let ((part nil) (part-passed 0) (part-failed 0) (part-seconds 0))
      (flet ((end-part ()
               (when part
                 (format t "~&  ~48A ~3D passed, ~D failed ~7,1F s~%"
                         (let ((dots (make-string (max 0 (- 46 (length part))) :initial-element #\.)))
                           (format nil "~A ~A" part dots))
                         part-passed part-failed part-seconds)
                 (finish-output))
               (setf part-passed 0 part-failed 0 part-seconds 0)))
        (loop for (claim-anchor . name) in selected
              for title = (gethash claim-anchor parts (format nil "section ~A" claim-anchor))
              do (unless (equal title part) (end-part) (setf part title))
                 (let* ((started (get-internal-real-time))
                        (results (let ((5am:*test-dribble* log) (*standard-output* log) (*error-output* log))
                                   (5am:run name)))
                        (seconds (/ (- (get-internal-real-time) started) internal-time-units-per-second 1.0))
                        (ok (claim-passed-p name results)))
                   (incf part-seconds seconds)
                   (push (list seconds claim-anchor name ok) times)
                   (if ok
                       (progn (incf passed) (incf part-passed))
                       (progn
                         (incf failed) (incf part-failed)
                         (push (cons claim-anchor name) failures)
                         (format t "~&FAILED: ~(~A~) -- ~A~%" name (5am::description (5am:get-test name)))
                         (dolist (line (failure-lines name results))
                           (format t "    ~A~%" line))
                         (let ((5am:*test-dribble* log)) (5am:explain! results))
                         (finish-output)))
                   (finish-output log)))
        (end-part))))
  (with-open-file (out *claim-times* :direction :output :if-exists :supersede :external-format :utf-8)
    (loop for (seconds claim-anchor name ok) in (reverse times)
          do (format out "~,3F	~A	~(~A~)	~:[FAILED~;passed~]~%" seconds claim-anchor name ok)))
  (when failures
    (format t "~&claims that failed: ~{~A~^, ~}~%"
            (mapcar (lambda (c) (format nil "~A ~(~A~)" (car c) (cdr c))) (reverse failures))))
  (finish-claims passed failed (if (zerop failed) 0 1)))
