;;;; tools/check-anchors.lisp -- are the anchors, links, claims and docstrings of physics.org consistent?
;;;;
;;;; Run by 'make check-anchors':
;;;;   sbcl --non-interactive --no-sysinit --no-userinit --load tools/check-anchors.lisp
;;;; Each problem is printed as "FILE:LINE: what is wrong", then a count, and the exit
;;;; status is 1.  A consistent page gives one summary line and status 0.
;;;;
;;;; What is checked:
;;;;  1. every heading has exactly one CUSTOM_ID, six uppercase letters or digits,
;;;;     and no two headings share one;
;;;;  2. every [[#ID]] or [[#ID][text]] link outside blocks names a CUSTOM_ID, and every
;;;;     [[file:PATH]] link names a file that exists (relative to the page);
;;;;  3. every (define-claim "ID" ...) names the anchor of the section it is written in;
;;;;  4. every paragraph starting "Claim:" is followed by a named test block, and every
;;;;     test block (one that defines claims) says :tangle tests/physics-tests.lisp,
;;;;     is named <ANCHOR>-<slug> and is preceded by a "Claim:" paragraph;
;;;;  5. every definition the loaded system registered (see section BSOZ3U of the page)
;;;;     ends its docstring with #ANCHOR of its section; a defmethod or a
;;;;     define-symbol-macro may have no docstring, anything else must have one;
;;;;  6. the block that registers a tangled file is that file's last chunk;
;;;;  7. the mutant records (tests/mutant-records.org, which tools/mutate.lisp reads) sit
;;;;     under headings that start with an anchor of the page, each paragraph is one record
;;;;     ("Equivalent mutant ~KEY~: ..." or "Surviving mutant ~KEY~: ..."), and the page
;;;;     keeps no :MUTANTS: drawer of its own.

(load (merge-pathnames "boot.lisp" *load-truename*))

(defpackage #:luv-physics-check-anchors
  (:use #:cl))

(in-package #:luv-physics-check-anchors)

(defparameter *page-name* "physics.org")
(defparameter *test-file* "tests/physics-tests.lisp")
(defparameter *records-name* "tests/mutant-records.org")
(defparameter *optional-docstring-kinds* '(:defmethod :define-symbol-macro))

(defvar *problems* '())

(defun problem (format-control &rest arguments)
  (push (apply #'format nil format-control arguments) *problems*))

(defun page-problem (line format-control &rest arguments)
  (problem "~A:~D: ~?" *page-name* line format-control arguments))

;;; Text helpers

(defun read-lines (pathname)
  "The lines of the UTF-8 file PATHNAME as a vector of strings."
  (with-open-file (in pathname :external-format :utf-8)
    (coerce (loop for line = (read-line in nil) while line collect line) 'vector)))

(defun blank-p (line)
  (every (lambda (c) (member c '(#\Space #\Tab))) line))

(defun trim (line)
  (string-trim '(#\Space #\Tab) line))

(defun starts-with (prefix string)
  (and (<= (length prefix) (length string))
       (string= prefix string :end2 (length prefix))))

(defun keyword-line-p (line keyword)
  "True if LINE, after its indentation, starts with KEYWORD, ignoring case."
  (let ((text (string-left-trim '(#\Space #\Tab) line)))
    (and (<= (length keyword) (length text))
         (string-equal keyword text :end2 (length keyword)))))

(defun heading-p (line)
  (let ((stars (or (position #\* line :test-not #'char=) (length line))))
    (and (plusp stars) (< stars (length line)) (char= #\Space (char line stars)))))

(defun anchor-p (string)
  (and (= 6 (length string))
       (every (lambda (c) (or (char<= #\A c #\Z) (char<= #\0 c #\9))) string)))

(defun paragraph-boundary-p (line)
  "True if LINE cannot belong to a prose paragraph."
  (or (blank-p line) (heading-p line) (keyword-line-p line "#+")
      (string-equal ":END:" (trim line))))

;;; The page

(defstruct src-block
  begin end header name name-line anchor (lines '()))

(defvar *lines*)
(defvar *anchors* (make-hash-table :test 'equal)
  "Each CUSTOM_ID of the page and the line of its heading.")
(defvar *section-anchor*)
(defvar *blocks* '())
(defvar *link-count* 0)
(defvar *claim-count* 0)

(defun line (n) (aref *lines* (1- n)))
(defun line-count () (length *lines*))

(defun check-headings ()
  "Check 1, and note the section anchor of every line."
  (let ((headings (loop for i from 1 to (line-count) when (heading-p (line i)) collect i)))
    (loop for (first next) on headings
          for last = (if next (1- next) (line-count))
          for ids = (when (and (< first last)
                               (string-equal ":PROPERTIES:" (trim (line (1+ first)))))
                      (loop for i from (+ first 2) to last
                            for text = (trim (line i))
                            until (string-equal ":END:" text)
                            when (starts-with ":CUSTOM_ID:" text)
                              collect (trim (subseq text 11))))
          do (cond ((null ids)
                    (page-problem first "heading has no CUSTOM_ID"))
                   ((rest ids)
                    (page-problem first "heading has ~D CUSTOM_IDs: ~{~A~^ ~}" (length ids) ids)))
             (dolist (id ids)
               (let ((seen (gethash id *anchors*)))
                 (cond ((not (anchor-p id))
                        (page-problem first "CUSTOM_ID ~S is not six uppercase letters or digits" id))
                       (seen
                        (page-problem first "CUSTOM_ID ~A is already the anchor of line ~D" id seen))
                       (t (setf (gethash id *anchors*) first)))))
             (when (= 1 (length ids))
               (loop for i from first to last
                     do (setf (aref *section-anchor* (1- i)) (first ids)))))))

(defun check-links (n)
  "Check 2 on line N."
  (let ((text (line n)))
    (loop for start = (search "[[#" text) then (search "[[#" text :start2 (1+ start))
          while start
          do (let* ((end (position #\] text :start start))
                    (id (subseq text (+ start 3) (or end (length text)))))
               (incf *link-count*)
               (unless (gethash id *anchors*)
                 (page-problem n "dangling link [[#~A]]" id))))
    (loop for start = (search "[[file:" text) then (search "[[file:" text :start2 (1+ start))
          while start
          do (let* ((end (position #\] text :start start))
                    (path (subseq text (+ start 7) (or end (length text)))))
               ;; a link quoted inside verbatim text (=... [[file:...]] ...=) is an example
               (unless (oddp (count #\= text :end start))
                 (incf *link-count*)
                 (unless (probe-file path)
                   (page-problem n "link to a missing file [[file:~A]]" path)))))))

(defun collect-blocks-and-links ()
  "Walk the page: check links outside blocks, and collect the source blocks."
  (let ((open nil))
    (loop for n from 1 to (line-count)
          for text = (line n)
          do (cond (open
                    (if (keyword-line-p text "#+end_")
                        (progn (when (src-block-p open)
                                 (setf (src-block-end open) n
                                       (src-block-lines open) (nreverse (src-block-lines open)))
                                 (push open *blocks*))
                               (setf open nil))
                        (when (src-block-p open)
                          (push text (src-block-lines open)))))
                   ((keyword-line-p text "#+begin_src")
                    (let ((named (and (> n 1) (keyword-line-p (line (1- n)) "#+name:"))))
                      (setf open (make-src-block
                                  :begin n
                                  :header (subseq (string-left-trim '(#\Space #\Tab) text) 11)
                                  :name (and named (trim (subseq (trim (line (1- n))) 7)))
                                  :name-line (and named (1- n))
                                  :anchor (aref *section-anchor* (1- n))))))
                   ((keyword-line-p text "#+begin_")
                    (setf open :other))
                   (t (check-links n)))))
  (setf *blocks* (nreverse *blocks*)))

(defun tangles-to-test-file-p (block)
  (search (format nil ":tangle ~A" *test-file*) (src-block-header block)))

(defun claim-anchors (block)
  "Each (LINE . ANCHOR) of a (define-claim \"ANCHOR\" ...) in BLOCK."
  (loop for text in (src-block-lines block)
        for n from (1+ (src-block-begin block))
        for start = (search "(define-claim \"" text)
        when start
          collect (let ((from (+ start (length "(define-claim \""))))
                    (cons n (subseq text from (or (position #\" text :start from) (length text)))))))

(defun claim-paragraph-start-p (n)
  (and (starts-with "Claim:" (line n))
       (or (= n 1) (paragraph-boundary-p (line (1- n))))))

(defun block-at (begin)
  (find begin *blocks* :key #'src-block-begin))

(defun check-claims ()
  "Checks 3 and 4."
  ;; Every "Claim:" paragraph is followed by a named test block.
  (loop for n from 1 to (line-count)
        when (and (claim-paragraph-start-p n) (null (find-if (lambda (b) (< (src-block-begin b) n (src-block-end b))) *blocks*)))
          do (let* ((end (loop for i from n to (line-count)
                               until (paragraph-boundary-p (line i))
                               finally (return i)))
                    (next (loop for i from end to (line-count)
                                unless (blank-p (line i)) return i))
                    (block (and next (< next (line-count))
                                (keyword-line-p (line next) "#+name:")
                                (block-at (1+ next)))))
               (unless (and block (claim-anchors block))
                 (page-problem n "Claim: paragraph is not followed by a named test block"))))
  (dolist (block *blocks*)
    (let ((claims (claim-anchors block))
          (anchor (src-block-anchor block)))
      ;; Every define-claim names its own section.
      (loop for (n . id) in claims
            do (cond ((not (gethash id *anchors*))
                      (page-problem n "define-claim names ~S, which is no anchor of the page" id))
                     ((not (equal id anchor))
                      (page-problem n "define-claim names ~A, but is written in section ~A" id anchor))))
      (when claims
        (incf *claim-count* (length claims))
        (unless (tangles-to-test-file-p block)
          (page-problem (src-block-begin block) "block defines claims but does not say :tangle ~A" *test-file*))
        (let ((name (src-block-name block)))
          (cond ((null name)
                 (page-problem (src-block-begin block) "test block has no #+name: ~A-<slug>" anchor))
                ((not (and anchor (starts-with (format nil "~A-" anchor) name) (> (length name) 7)))
                 (page-problem (src-block-name-line block) "test block name ~A does not start with ~A-" name anchor))))
        ;; Every test block is preceded by a "Claim:" paragraph.
        (let* ((above (1- (or (src-block-name-line block) (src-block-begin block))))
               (last (loop for i downfrom above to 1
                           unless (blank-p (line i)) return i))
               (first (and last (not (paragraph-boundary-p (line last)))
                           (loop for i downfrom last to 1
                                 when (or (= i 1) (paragraph-boundary-p (line (1- i)))) return i))))
          (unless (and first (claim-paragraph-start-p first))
            (page-problem (src-block-begin block) "test block is not preceded by a Claim: paragraph")))))))

;;; The loaded system

(defun relative (pathname)
  (enough-namestring pathname cl-user::*luv-root*))

(defun check-definitions ()
  "Check 5, on the registry of the loaded system."
  (let ((*package* (find-package '#:luv-physics))
        (count 0))
    (dolist (record (symbol-value (find-symbol "*DEFINITIONS*" '#:luv-physics)) count)
      (destructuring-bind (&key name kind anchor file line org-line docstring) record
        (incf count)
        (flet ((report (format-control &rest arguments)
                 (problem "~A:~D (~A:~:[?~;~:*~D~]): ~(~A~) ~(~S~): ~?"
                          file line *page-name* org-line kind name format-control arguments)))
          (let ((ending (format nil "#~A" anchor))
                (doc (and docstring (string-right-trim '(#\Space #\Tab #\Newline) docstring))))
            (cond ((null anchor)
                   (report "is not in a chunk tangled from an anchored section"))
                  ((null doc)
                   (unless (member kind *optional-docstring-kinds*)
                     (report "has no docstring; end one with ~A" ending)))
                  ((not (and (>= (length doc) (length ending))
                             (string= ending doc :start2 (- (length doc) (length ending)))))
                   (report "docstring does not end with ~A" ending)))))))))

(defun check-registration-last ()
  "Check 6."
  (dolist (source (symbol-value (find-symbol "*REGISTERED-FILES*" '#:luv-physics)))
    (let* ((lines (read-lines source))
           (register (position-if (lambda (text) (starts-with "(register-tangled-file " text))
                                  lines :from-end t)))
      (if (null register)
          (problem "~A: does not register its definitions" (relative source))
          (loop for i from (1+ register) below (length lines)
                for anchor = (funcall (find-symbol "LINK-COMMENT-ANCHOR" '#:luv-physics) (aref lines i))
                when anchor
                  do (problem "~A:~D: the chunk from #~A comes after the registration block; ~
                               insert sections before the closing section"
                              (relative source) (1+ i) anchor))))))

;;; The mutant records

(defun check-mutant-records ()
  "Check 7; return the number of records."
  (loop for i from 1 to (line-count)
        when (string-equal ":MUTANTS:" (trim (line i)))
          do (page-problem i "a :MUTANTS: drawer: the records belong in ~A" *records-name*))
  (let ((path (merge-pathnames *records-name* cl-user::*luv-root*)) (records 0) (start t))
    (if (not (probe-file path))
        (problem "~A: no such file" *records-name*)
        (loop with lines = (read-lines path)
              for text across lines
              for n from 1
              do (cond ((blank-p text) (setf start t))
                       ((starts-with "#" text))
                       ((heading-p text)
                        (let* ((words (trim (string-left-trim "*" text)))
                               (anchor (subseq words 0 (or (position #\Space words) (length words)))))
                          (unless (gethash anchor *anchors*)
                            (problem "~A:~D: ~S is not an anchor of the page" *records-name* n anchor)))
                        (setf start t))
                       (start
                        (if (and (or (starts-with "Equivalent mutant ~" text)
                                     (starts-with "Surviving mutant ~" text))
                                 (search "~:" text))
                            (incf records)
                            (problem "~A:~D: a paragraph that is not a mutant record" *records-name* n))
                        (setf start nil)))))
    records))

;;; Run

(defun main ()
  (let ((page (merge-pathnames *page-name* cl-user::*luv-root*))
        (definitions 0) (records 0))
    (unless (probe-file page)
      (format t "~&check-anchors: ~A: no such file~%" *page-name*)
      (sb-ext:exit :code 1))
    (setf *lines* (read-lines page)
          *section-anchor* (make-array (length *lines*) :initial-element nil))
    (check-headings)
    (collect-blocks-and-links)
    (check-claims)
    (setf records (check-mutant-records))
    (if (cl-user::luv-load-systems "luv-physics")
        (problem "luv-physics did not load, so its definitions were not checked")
        (progn (setf definitions (check-definitions))
               (check-registration-last)))
    (cond (*problems*
           (format t "~&~{~A~%~}check-anchors: ~D problem~:P~%" (reverse *problems*) (length *problems*))
           (finish-output)
           (sb-ext:exit :code 1))
          (t
           (format t "~&check-anchors: ~A is consistent: ~D anchors, ~D links, ~D claims, ~D definitions, ~D mutant records~%"
                   *page-name* (hash-table-count *anchors*) *link-count* *claim-count* definitions records)
           (finish-output)))))

(main)
